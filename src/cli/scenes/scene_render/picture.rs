//! The picture model: options, the travel-time field of the goal, agents and routes.

use super::error::RenderError;
use super::routes::{sample_agents, trace_route, Route};
use crowdtouch::crowd::environment::eikonal::{
    cost_field_into, sample, CostInputs, CostWeights, EikonalError, Fmm, Grid, Sources,
};
use crowdtouch::crowd::environment::{ObstacleId, Scene, SceneGrid};
use crowdtouch::geom::{Rect, Vec2};

/// Most agents drawn.
pub const MAX_AGENTS: usize = 10_000;
/// Default goal: this far in from the east edge of the bounds, at mid-height (m).
pub const DEFAULT_GOAL_INSET_M: f64 = 1.0;

/// What to draw.
#[derive(Clone, Debug)]
pub struct Options {
    /// Goal (m); `None` for the default.
    pub goal: Option<Vec2>,
    /// Number of agents.
    pub agents: usize,
    /// Scene time (s).
    pub t_s: f64,
    /// Field grid cell size (m).
    pub cell_m: f64,
    /// Agents' preferred speed `f` (m/s).
    pub preferred_speed_m_s: f64,
    /// Crowd start rectangle (m).
    pub start: Rect,
}

impl Options {
    pub(super) fn check(&self) -> Result<(), RenderError> {
        if !(self.cell_m.is_finite() && self.cell_m > 0.0) {
            return Err(RenderError::Usage(format!(
                "--cell-m must be a positive number of metres, got {}",
                self.cell_m
            )));
        }
        if !self.t_s.is_finite() {
            return Err(RenderError::Usage(format!(
                "--t must be a finite number of seconds, got {}",
                self.t_s
            )));
        }
        if self.agents > MAX_AGENTS {
            return Err(RenderError::Usage(format!(
                "--agents must be at most {MAX_AGENTS}, got {}",
                self.agents
            )));
        }
        Ok(())
    }
}

/// The computed picture: field, agents and routes.
pub struct Picture {
    pub(super) grid: Grid,
    /// Cells agents cannot enter: obstacles at `t`, and cells whose centre lies
    /// outside the bounds.
    pub(super) blocked: Vec<bool>,
    pub(super) phi: Vec<f64>,
    /// The goal (m).
    pub goal: Vec2,
    /// Largest finite `Φ` (s).
    pub phi_max: f64,
    /// Agent start positions (m).
    pub agents: Vec<Vec2>,
    /// One route per agent with a finite `Φ`, in agent order.
    pub routes: Vec<Route>,
}

impl Picture {
    /// Rasterises the scene, solves the field from the goal and traces the routes.
    ///
    /// # Errors
    /// [`RenderError::Usage`] for a grid that is too fine or a goal outside the
    /// bounds, inside an obstacle or in a blocked cell.
    pub fn compute(scene: &Scene, o: &Options) -> Result<Picture, RenderError> {
        let b = scene.bounds();
        let mut sg = SceneGrid::for_bounds(b, o.cell_m).map_err(|e| {
            RenderError::Usage(format!("--cell-m {}: {e} for the bounds", o.cell_m))
        })?;
        scene.rasterize_into(&mut sg, o.t_s);
        let grid = Grid::new(sg.cols, sg.rows, sg.cell_m, sg.origin)
            .map_err(|e| RenderError::Usage(format!("--cell-m {}: {e}", o.cell_m)))?;
        let blocked: Vec<bool> = (0..grid.len())
            .map(|i| sg.blocked[i] || !b.contains(grid.center(i)))
            .collect();
        let mut cost = vec![0.0; grid.len()];
        let weights = CostWeights {
            alpha_per_m: 0.0,
            beta_per_s: 1.0,
            gamma_per_s: 0.0,
        };
        let inputs = CostInputs {
            blocked: &blocked,
            speed_factor: &sg.speed_factor,
            discomfort: None,
        };
        cost_field_into(&grid, weights, o.preferred_speed_m_s, inputs, &mut cost)
            .map_err(|e| RenderError::Failed(format!("crowdtouch: error: cost field: {e}")))?;
        let goal = match o.goal {
            Some(g) => {
                check_goal(scene, &grid, &blocked, g, o)?;
                g
            }
            None => default_goal(b, &grid, &blocked).ok_or_else(|| {
                RenderError::Usage("the scene has no free cell for a goal; give --goal".into())
            })?,
        };
        let mut phi = vec![0.0; grid.len()];
        Fmm::new()
            .solve_into(&grid, &cost, Sources::Points(&[goal]), &mut phi)
            .map_err(|e| match e {
                EikonalError::SourceBlocked { .. } => RenderError::Usage(format!(
                    "--goal ({}, {}) lies in a blocked cell of the {} m grid; move it away from the obstacle or use a smaller --cell-m",
                    goal.x, goal.y, o.cell_m
                )),
                e => RenderError::Failed(format!("crowdtouch: error: fast marching: {e}")),
            })?;
        let phi_max = phi
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        let agents = sample_agents(o.start, o.agents, &grid, &blocked);
        let routes = agents
            .iter()
            .filter(|&&p| sample(&grid, &phi, p).is_finite())
            .map(|&p| trace_route(&grid, &phi, p, goal))
            .collect();
        Ok(Picture {
            grid,
            blocked,
            phi,
            goal,
            phi_max,
            agents,
            routes,
        })
    }
}

/// Rejects a goal outside the bounds, in an obstacle, or in a blocked cell.
fn check_goal(
    scene: &Scene,
    grid: &Grid,
    blocked: &[bool],
    g: Vec2,
    o: &Options,
) -> Result<(), RenderError> {
    let b = scene.bounds();
    if !b.contains(g) {
        return Err(RenderError::Usage(format!(
            "--goal ({}, {}) is outside the scene bounds ({}, {})..({}, {})",
            g.x, g.y, b.min[0], b.min[1], b.max[0], b.max[1]
        )));
    }
    if let Some(id) = scene.obstacle_at(g, o.t_s) {
        let what = match id {
            ObstacleId::Static(i) => format!("obstacle {:?}", scene.obstacles()[i].name),
            ObstacleId::Dynamic(i) => format!(
                "moving obstacle {:?} (at t = {} s)",
                scene.dynamic()[i].name,
                o.t_s
            ),
        };
        return Err(RenderError::Usage(format!(
            "--goal ({}, {}) is inside {what}",
            g.x, g.y
        )));
    }
    if grid.cell_of(g).is_some_and(|i| blocked[i]) {
        return Err(RenderError::Usage(format!(
            "--goal ({}, {}) lies in a blocked cell of the {} m grid; move it away from the obstacle or use a smaller --cell-m",
            g.x, g.y, o.cell_m
        )));
    }
    Ok(())
}

/// The default goal: [`DEFAULT_GOAL_INSET_M`] in from the east edge at mid-height,
/// or the centre of the free cell nearest to it (ties: lowest index).
fn default_goal(b: Rect, grid: &Grid, blocked: &[bool]) -> Option<Vec2> {
    let inset = DEFAULT_GOAL_INSET_M.min(0.5 * b.width());
    let p = Vec2::new(b.max[0] - inset, 0.5 * (b.min[1] + b.max[1]));
    if grid.cell_of(p).is_some_and(|i| !blocked[i]) {
        return Some(p);
    }
    (0..grid.len())
        .filter(|&i| !blocked[i])
        .min_by(|&i, &j| {
            let (di, dj) = (
                (grid.center(i) - p).norm_squared(),
                (grid.center(j) - p).norm_squared(),
            );
            di.total_cmp(&dj).then(i.cmp(&j))
        })
        .map(|i| grid.center(i))
}
