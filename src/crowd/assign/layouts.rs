//! The assignment instances the benchmarks and tests solve: uniform points, and the
//! layouts a table produces that are hard for a nearest-goal search (a crowd pinched
//! into a disk, stretched into a line, dragged into a corner or off its formation).
//!
//! `crowdtouch bench assign --layout`, `benches/assign.rs` and the solver's tests all
//! draw from here, so they see the same points. World units are metres; the
//! formation is a 4 m × 3 m rectangle unless the layout says otherwise.

use crate::geom::Vec2;
use crate::rng::SplitMix64;

/// Where the agents and the goals are.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Layout {
    /// Agents and goals uniform in the unit square.
    Uniform,
    /// Agents in a disk of radius 0.3 m at the centre of the 4 × 3 m formation, goals
    /// uniform in it (a crowd that was pinched, spreading out again).
    Clustered,
    /// Agents uniform in the formation, goals in the 0.3 m disk (a pinch).
    Pinched,
    /// Agents on an 8 m × 5 cm line through the formation's centre, goals uniform in
    /// it.
    Line,
    /// Agents uniform in the formation, goals on the line (a stretch).
    ToLine,
    /// Agents in a 2 × 2 m square at the formation's corner, goals uniform in it.
    Corner,
    /// Agents uniform in the formation, goals uniform in the same rectangle 3 m to
    /// the east (a drag, or a reset after one).
    Shifted,
}

impl Layout {
    /// Every layout, in the order the benchmarks report them.
    pub const ALL: [Layout; 7] = [
        Layout::Uniform,
        Layout::Clustered,
        Layout::Pinched,
        Layout::Line,
        Layout::ToLine,
        Layout::Corner,
        Layout::Shifted,
    ];

    /// The name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Layout::Uniform => "uniform",
            Layout::Clustered => "clustered",
            Layout::Pinched => "pinched",
            Layout::Line => "line",
            Layout::ToLine => "to-line",
            Layout::Corner => "corner",
            Layout::Shifted => "shifted",
        }
    }

    /// The layout with this [`Layout::name`].
    pub fn from_name(name: &str) -> Option<Layout> {
        Layout::ALL.into_iter().find(|l| l.name() == name)
    }

    /// `n` agents and `n` goals drawn from `rng` (agents first).
    pub fn instance(self, rng: &mut SplitMix64, n: usize) -> (Vec<Vec2>, Vec<Vec2>) {
        let agents = (0..n).map(|_| self.agent_region().sample(rng)).collect();
        let goals = (0..n).map(|_| self.goal_region().sample(rng)).collect();
        (agents, goals)
    }

    /// The width and height of the goals' region (m): the warm benchmarks move each
    /// goal by up to 2 % of them per frame, so a formation drifts without changing
    /// its shape (a line stays a line).
    pub fn goal_extent(self) -> Vec2 {
        match self.goal_region() {
            Region::Rect { w, h, .. } => Vec2::new(w, h),
            Region::Disk { r, .. } => Vec2::new(2.0 * r, 2.0 * r),
        }
    }

    fn agent_region(self) -> Region {
        match self {
            Layout::Uniform => UNIT,
            Layout::Clustered => DISK,
            Layout::Line => LINE,
            Layout::Corner => Region::Rect {
                x: 0.0,
                y: 0.0,
                w: 2.0,
                h: 2.0,
            },
            Layout::Pinched | Layout::ToLine | Layout::Shifted => FORMATION,
        }
    }

    fn goal_region(self) -> Region {
        match self {
            Layout::Uniform => UNIT,
            Layout::Pinched => DISK,
            Layout::ToLine => LINE,
            Layout::Shifted => Region::Rect {
                x: 3.0,
                y: 0.0,
                w: 4.0,
                h: 3.0,
            },
            Layout::Clustered | Layout::Line | Layout::Corner => FORMATION,
        }
    }
}

/// A region points are drawn uniformly from.
#[derive(Copy, Clone, Debug)]
enum Region {
    /// Corner `(x, y)`, size `w × h` (m).
    Rect { x: f64, y: f64, w: f64, h: f64 },
    /// Centre `(x, y)`, radius `r` (m).
    Disk { x: f64, y: f64, r: f64 },
}

const UNIT: Region = Region::Rect {
    x: 0.0,
    y: 0.0,
    w: 1.0,
    h: 1.0,
};
const FORMATION: Region = Region::Rect {
    x: 0.0,
    y: 0.0,
    w: 4.0,
    h: 3.0,
};
const DISK: Region = Region::Disk {
    x: 2.0,
    y: 1.5,
    r: 0.3,
};
const LINE: Region = Region::Rect {
    x: -2.0,
    y: 1.475,
    w: 8.0,
    h: 0.05,
};

impl Region {
    fn sample(self, rng: &mut SplitMix64) -> Vec2 {
        match self {
            Region::Rect { x, y, w, h } => Vec2::new(x + w * rng.unit(), y + h * rng.unit()),
            Region::Disk { x, y, r } => {
                // Uniform in area: radius ∝ sqrt(u).
                let rho = r * rng.unit().sqrt();
                let phi = std::f64::consts::TAU * rng.unit();
                Vec2::new(x + rho * phi.cos(), y + rho * phi.sin())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_points_fall_in_their_regions() {
        for l in Layout::ALL {
            assert_eq!(Layout::from_name(l.name()), Some(l));
            let (a, g) = l.instance(&mut SplitMix64::new(1), 200);
            assert_eq!((a.len(), g.len()), (200, 200));
            for p in a.iter().chain(&g) {
                assert!(
                    p.x > -2.01 && p.x < 7.01 && p.y > -0.01 && p.y < 3.01,
                    "{l:?} {p}"
                );
            }
        }
        assert_eq!(Layout::from_name("round"), None);
        let (a, _) = Layout::Clustered.instance(&mut SplitMix64::new(2), 500);
        assert!(a
            .iter()
            .all(|p| (p - Vec2::new(2.0, 1.5)).norm() <= 0.3 + 1e-12));
    }

    #[test]
    fn the_uniform_layout_draws_the_points_of_the_earlier_benchmarks() {
        // Agents then goals, x then y, uniform in the unit square.
        let mut rng = SplitMix64::new(5);
        let (a, g) = Layout::Uniform.instance(&mut SplitMix64::new(5), 3);
        let expect: Vec<Vec2> = (0..6).map(|_| Vec2::new(rng.unit(), rng.unit())).collect();
        assert_eq!([a, g].concat(), expect);
    }
}
