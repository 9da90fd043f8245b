//! How a transform moves the agents: the mover and its parameters (SI units),
//! apart from `run.rs` so that the force and baseline modules read them without an
//! import cycle.

/// What moves the agents.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Mover {
    /// The paper's social force model (eqs. 7–10, 21–23) with feedback (eqs. 18–19).
    #[default]
    SocialForce,
    /// ORCA (the comparison of section 5.4) on the same pairing.
    Orca,
    /// RVO (VdBLM08) by sampled velocities, as its library ran it (`rvo.rs`).
    Rvo,
    /// OpenSteer-style steering behaviours (Reynolds 1999; `steer.rs`).
    Steering,
}

/// The subgroup attraction of eq. 21 (formation-transform section 3.5), or the
/// paper's manipulation of a subgroup as a whole on its Delaunay graph (section 3,
/// pipeline step 3). `social_groups.rs` has the formulas.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum SubgroupAttraction {
    /// Ours: a bounded pull towards the agent's place in its group (the group's
    /// centroid plus its offset blended from source to target layout), at most `A'`.
    #[default]
    Place,
    /// Eq. 21 as printed: `A' e^{d}` towards every other member, `d` in metres;
    /// unbounded, only the run's `max_accel` clamp bounds the total.
    AsPrinted,
    /// A guess at a misprint in eq. 21: `A' e^{−d/B'}` towards every other
    /// member (eq. 22 without its `1/d`, attracting).
    Decaying,
    /// Our reading of section 3's "each subgroup is manipulated as a whole using a
    /// DT graph" (no equation given): the Delaunay edges of each group's source
    /// layout are damped springs whose rest length goes from the source to the
    /// target length as the group advances.
    DelaunayGraph,
}

impl SubgroupAttraction {
    /// Every variant, in the order the CLI lists them.
    pub const ALL: [SubgroupAttraction; 4] = [
        SubgroupAttraction::Place,
        SubgroupAttraction::AsPrinted,
        SubgroupAttraction::Decaying,
        SubgroupAttraction::DelaunayGraph,
    ];

    /// The name the CLI, the config and the JSON use.
    pub fn name(self) -> &'static str {
        match self {
            SubgroupAttraction::Place => "place",
            SubgroupAttraction::AsPrinted => "as-printed",
            SubgroupAttraction::Decaying => "decaying",
            SubgroupAttraction::DelaunayGraph => "dt",
        }
    }

    /// The variant named `name` (see [`name`](Self::name)).
    pub fn from_name(name: &str) -> Option<SubgroupAttraction> {
        Self::ALL.into_iter().find(|a| a.name() == name)
    }
}

/// How a transform moves the agents. Lengths in metres, times in seconds,
/// accelerations (forces on a unit mass) in m/s².
#[derive(Clone, Debug, PartialEq)]
pub struct MoveParams {
    /// What moves them.
    pub mover: Mover,
    /// Agent radius (m).
    pub radius_m: f64,
    /// `v⁰`: desired speed (m/s), the mean of the agents' own.
    pub desired_speed_m_s: f64,
    /// Each agent's own desired speed is drawn uniformly within this much of
    /// `desired_speed_m_s` (m/s); eq. 19 then evens them out within bins.
    pub desired_speed_spread_m_s: f64,
    /// Most speed of any agent (m/s).
    pub max_speed_m_s: f64,
    /// Most acceleration of any agent (m/s²).
    pub max_accel_m_s2: f64,
    /// `τ`: relaxation time of the driving force, eq. 8 (s).
    pub tau_s: f64,
    /// Arrival ramp: an agent wants at most `sqrt(2 · arrival_decel · distance)`,
    /// braking evenly to its target (m/s²).
    pub arrival_decel_m_s2: f64,
    /// The forces other than the driving force fade out linearly over this last
    /// stretch before the target (m), so neighbours cannot hold an agent off it.
    pub fade_m: f64,
    /// `A` of eqs. 9–10 (m/s²).
    pub repulsion_a_m_s2: f64,
    /// `B` of eqs. 9–10 (m).
    pub repulsion_b_m: f64,
    /// `A` of eq. 9 for the scene's obstacles (m/s²).
    pub obstacle_a_m_s2: f64,
    /// `A'` of eqs. 21–22 (m/s²).
    pub subgroup_a_m_s2: f64,
    /// `B'` of eqs. 21–22 (m).
    pub subgroup_b_m: f64,
    /// Which subgroup attraction acts (with [`subgroup_forces`](Self::subgroup_forces)).
    pub subgroup_attraction: SubgroupAttraction,
    /// [`SubgroupAttraction::DelaunayGraph`]: each edge's spring stiffness, the
    /// acceleration per metre of stretch ((m/s²)/m); not scaled by
    /// [`with_radius`](Self::with_radius).
    pub subgroup_dt_stiffness_m_s2_per_m: f64,
    /// [`SubgroupAttraction::DelaunayGraph`]: each edge's damping, the
    /// acceleration per m/s of relative speed along the edge ((m/s²)/(m/s)).
    pub subgroup_dt_damping_m_s2_per_m_s: f64,
    /// Agents (and obstacles) farther apart than this exert no social force (m).
    pub interaction_range_m: f64,
    /// `ξ`: the fluctuation of eq. 7, uniform in a disc of this radius (m/s²).
    pub fluctuation_m_s2: f64,
    /// `R`: side of the mutual-information bins (m), eqs. 12–13, 18–19.
    pub bin_m: f64,
    /// `K`: heading sectors (eq. 14) and speed bins.
    pub sectors: usize,
    /// Mutual-information feedback on heading and desired speed (eqs. 18–19).
    pub feedback: bool,
    /// Subgroup attraction and cross-group repulsion (eqs. 21–23).
    pub subgroup_forces: bool,
    /// Ours, not the paper's: the forces other than the driving one fade out over
    /// the last [`fade_m`](Self::fade_m) before the target. Off: they act in full
    /// until an agent settles (or, without settling, always).
    pub fades: bool,
    /// Ours: an arrived agent slow enough settles (stops and holds; no force acts
    /// on it, and ORCA gives it almost no share of avoidance). Off: arrived agents
    /// keep being driven to their targets and keep avoiding, as in RVO2, and a run
    /// ends when every agent is within [`arrive_m`](Self::arrive_m) of its target.
    pub settling: bool,
    /// Ours: after each substep, pairs closer than two radii are moved apart
    /// positionally, by right of way (step 5 of `run.rs`). Off: only the mover
    /// keeps agents apart (overlaps are then measured, not removed).
    pub contacts: bool,
    /// Ours: two blocked agents heading for targets beyond each other exchange
    /// targets (step 6 of `run.rs`). Off: targets stay as the pairing gave them.
    pub exchanges: bool,
    /// An agent within this distance of its target has arrived (m).
    pub arrive_m: f64,
    /// An arrived agent slower than this settles: it stops and holds (m/s).
    pub settle_speed_m_s: f64,
    /// The transform ends after this long even if not every agent arrived (s).
    pub timeout_s: f64,
    /// A step longer than this is taken in substeps (s).
    pub max_substep_s: f64,
    /// Rounds of positional overlap resolution after each substep.
    pub overlap_rounds: usize,
}

impl MoveParams {
    /// These parameters with only what formation-transform has: no fades, no
    /// settling, no positional contacts, no exchanges of targets (the paper's
    /// method as written: social forces with subgroups and feedback, eqs. 7–23).
    ///
    /// Without settling, neighbours' repulsion holds agents a little off their
    /// targets for good, so an agent counts as arrived within one agent radius of
    /// its target (its disc covers it) rather than `arrive_m`'s few centimetres.
    pub fn paper(mut self) -> MoveParams {
        self.arrive_m = self.arrive_m.max(self.radius_m);
        self.fades = false;
        self.settling = false;
        self.contacts = false;
        self.exchanges = false;
        self
    }

    /// ORCA as RVO2 runs it (the paper's Table 3 baseline): no feedback, no
    /// exchanges, no positional contacts, and arrived agents keep avoiding.
    pub fn rvo2_orca(mut self) -> MoveParams {
        self.mover = Mover::Orca;
        self.feedback = false;
        self.subgroup_forces = false;
        self.paper()
    }

    /// RVO as the RVO library ran it (the paper's Table 3 baseline, `rvo.rs`):
    /// like [`rvo2_orca`](Self::rvo2_orca), none of the project's additions.
    pub fn rvo(self) -> MoveParams {
        MoveParams {
            mover: Mover::Rvo,
            ..self.rvo2_orca()
        }
    }

    /// OpenSteer-style steering (the paper's Table 3 baseline, `steer.rs`): like
    /// [`rvo2_orca`](Self::rvo2_orca), none of the project's additions.
    pub fn steering(self) -> MoveParams {
        MoveParams {
            mover: Mover::Steering,
            ..self.rvo2_orca()
        }
    }

    /// These parameters for agents of radius `radius_m`. Agents smaller than
    /// `self.radius_m` (a crowd shrunk to fit its area) get every length of the
    /// model scaled by the ratio — interaction range, `B`, `B'`, the fade, the
    /// feedback's bins `R` and the arrival distance — so that an agent meets as many
    /// neighbours as at full size (at a quarter of the radius and the same range, a
    /// dense crowd has sixteen times as many pairs within range). Speeds,
    /// accelerations and times stay. Larger agents keep the lengths as they are.
    pub fn with_radius(mut self, radius_m: f64) -> MoveParams {
        let k = radius_m / self.radius_m;
        if k.is_finite() && k > 0.0 && k < 1.0 {
            self.interaction_range_m *= k;
            self.repulsion_b_m *= k;
            self.subgroup_b_m *= k;
            self.fade_m *= k;
            self.bin_m *= k;
            self.arrive_m *= k;
        }
        self.radius_m = radius_m;
        self
    }
}

impl Default for MoveParams {
    /// People-sized agents: radius 0.25 m, walking at 1.3 m/s.
    fn default() -> MoveParams {
        MoveParams {
            mover: Mover::SocialForce,
            radius_m: 0.25,
            desired_speed_m_s: 1.3,
            desired_speed_spread_m_s: 0.2,
            max_speed_m_s: 2.0,
            max_accel_m_s2: 4.0,
            tau_s: 0.4,
            arrival_decel_m_s2: 0.6,
            fade_m: 1.0,
            repulsion_a_m_s2: 2.0,
            repulsion_b_m: 0.3,
            obstacle_a_m_s2: 3.0,
            subgroup_a_m_s2: 1.0,
            subgroup_b_m: 0.5,
            subgroup_attraction: SubgroupAttraction::Place,
            subgroup_dt_stiffness_m_s2_per_m: 10.0,
            subgroup_dt_damping_m_s2_per_m_s: 5.0,
            interaction_range_m: 1.2,
            fluctuation_m_s2: 0.1,
            bin_m: 2.0,
            sectors: 8,
            feedback: true,
            subgroup_forces: true,
            fades: true,
            settling: true,
            contacts: true,
            exchanges: true,
            arrive_m: 0.05,
            settle_speed_m_s: 0.6,
            timeout_s: 120.0,
            max_substep_s: 1.0 / 30.0,
            overlap_rounds: 16,
        }
    }
}
