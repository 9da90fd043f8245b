//! `crowdtouch scene render`: a picture of a scene and of how agents cross it.
//!
//! Draws, in world metres (x right, y down, as `replay --svg`):
//! * the travel-time field `Φ` of one goal as a heat map with iso-time contours
//!   (mesh-formation-control section 6.2: the scene rasterised into a
//!   [`SceneGrid`], the unit cost of eq. 7 from [`cost_field_into`], fast marching
//!   from the goal with [`Fmm::solve_into`]); blocked and unreachable cells in their
//!   own colours;
//! * the world bounds, static obstacles (filled), travel-speed patches coloured by
//!   motion type, moving obstacles and patches where they are at `--t` with their
//!   paths dashed, checkpoints outlined with their formation names;
//! * agents sampled on a lattice in the default crowd start rectangle and each
//!   agent's route to the goal, traced by descending `Φ` ([`descent_direction`]);
//! * a legend (Table 1 motion types and speed factors), the colour scale, a title
//!   line and a scale bar.
//!
//! # Units of `Φ`
//! Seconds of travel at the agents' preferred speed `f` (the config's
//! `crowd.max_speed_m_s`): eq. 7 with `α = 0`, `β = 1 /s`, `γ = 0` gives the unit
//! cost `C = 1 / (f · TravelSpeed(x))` in seconds per metre. Without discomfort the
//! assignment's default weights (`α = β = 1`) give the same field scaled by
//! `(α f + β) / β`, so the routes are the same.
//!
//! The output depends only on the scene file and the arguments: no clock, no
//! randomness, numbers printed with fixed precision, so the same input gives the
//! same bytes.

use crowdtouch::config::Config;
use crowdtouch::crowd::environment::eikonal::{
    cost_field_into, descent_direction, sample, CostInputs, CostWeights, EikonalError, Fmm, Grid,
    Sources,
};
use crowdtouch::crowd::environment::{
    DynamicKind, ObstacleId, Part, PathMode, Placement, Scene, SceneGrid,
};
use crowdtouch::geom::{Rect, Vec2};
use crowdtouch::vocab::MotionType;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Default cell size of the field grid (m).
pub const DEFAULT_CELL_M: f64 = 0.05;
/// Default number of agents.
pub const DEFAULT_AGENTS: usize = 40;
/// Most agents drawn.
pub const MAX_AGENTS: usize = 10_000;
/// The heat map has at most this many blocks across …
pub const MAX_HEAT_COLS: usize = 160;
/// … and this many down.
pub const MAX_HEAT_ROWS: usize = 90;
/// Colour levels of the heat map and its scale.
pub const HEAT_LEVELS: usize = 40;
/// Default goal: this far in from the east edge of the bounds, at mid-height (m).
pub const DEFAULT_GOAL_INSET_M: f64 = 1.0;
/// Route step, in cells.
pub const ROUTE_STEP_CELLS: f64 = 0.5;
/// Route step budget, per cell of the grid's width plus height.
pub const ROUTE_STEPS_PER_CELL: usize = 8;
/// Routes are simplified to within this many pixels (Douglas–Peucker).
pub const ROUTE_TOLERANCE_PX: f64 = 0.4;
/// Drawing scale: the map fits in this many pixels across …
const MAP_W_PX: f64 = 960.0;
/// … and this many down.
const MAP_H_PX: f64 = 540.0;
const MARGIN_PX: f64 = 14.0;
const TITLE_PX: f64 = 46.0;
const FOOTER_PX: f64 = 44.0;
const PANEL_PX: f64 = 250.0;

/// `crowdtouch scene render` arguments.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene file (RON).
    pub file: PathBuf,
    /// Output SVG file.
    #[arg(long, short)]
    pub out: PathBuf,
    /// Goal of the field, `X,Y` in metres (default: 1 m in from the east edge at
    /// mid-height, or the nearest free cell to it).
    #[arg(long, value_name = "X,Y", value_parser = parse_point, allow_hyphen_values = true)]
    pub goal: Option<[f64; 2]>,
    /// Number of agents, on a lattice in the config's crowd start rectangle
    /// (blocked cells skipped).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_AGENTS)]
    pub agents: usize,
    /// Scene time (s): where moving obstacles and patches are.
    #[arg(
        long = "t",
        value_name = "S",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub t_s: f64,
    /// Cell size of the field grid (m).
    #[arg(long, value_name = "M", default_value_t = DEFAULT_CELL_M)]
    pub cell_m: f64,
}

/// Parses `X,Y` (metres).
fn parse_point(s: &str) -> Result<[f64; 2], String> {
    let bad = || format!("expected X,Y in metres (e.g. 14.5,4.5), got {s:?}");
    let (x, y) = s.split_once(',').ok_or_else(bad)?;
    let x: f64 = x.trim().parse().map_err(|_| bad())?;
    let y: f64 = y.trim().parse().map_err(|_| bad())?;
    if !(x.is_finite() && y.is_finite()) {
        return Err(bad());
    }
    Ok([x, y])
}

/// Why a picture could not be made.
#[derive(Debug, PartialEq)]
pub enum RenderError {
    /// A bad argument (exit code 2).
    Usage(String),
    /// A bad scene file or an output that cannot be written (exit code 1).
    Failed(String),
}

/// Runs `scene render`; returns the exit code.
pub fn render(a: RenderArgs) -> i32 {
    match run(&a) {
        Ok(summary) => {
            println!("{summary}");
            0
        }
        Err(RenderError::Usage(m)) => {
            eprintln!("crowdtouch: error: {m}");
            2
        }
        Err(RenderError::Failed(m)) => {
            eprintln!("{m}");
            1
        }
    }
}

fn run(a: &RenderArgs) -> Result<String, RenderError> {
    let cfg = Config::embedded_default();
    let opts = Options {
        goal: a.goal.map(|[x, y]| Vec2::new(x, y)),
        agents: a.agents,
        t_s: a.t_s,
        cell_m: a.cell_m,
        preferred_speed_m_s: cfg.crowd.max_speed_m_s,
        start: cfg.crowd.formation,
    };
    opts.check()?;
    let scene = Scene::load(&a.file, cfg.crowd.agent_radius_m)
        .map_err(|e| RenderError::Failed(e.to_string()))?;
    let pic = Picture::compute(&scene, &opts)?;
    let svg = pic.svg(&scene, &opts);
    std::fs::write(&a.out, &svg).map_err(|e| {
        RenderError::Failed(format!(
            "crowdtouch: error: writing {}: {e}",
            a.out.display()
        ))
    })?;
    Ok(format!(
        "{}: {:?}, goal ({:.2}, {:.2}), {} agents, {} of {} routes reach the goal, Φ up to {:.1} s; {} bytes",
        display(&a.out),
        scene.name(),
        pic.goal.x,
        pic.goal.y,
        pic.agents.len(),
        pic.routes.iter().filter(|r| r.reached).count(),
        pic.routes.len(),
        pic.phi_max,
        svg.len()
    ))
}

fn display(p: &Path) -> String {
    p.display().to_string()
}

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
    fn check(&self) -> Result<(), RenderError> {
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

/// One agent's route.
#[derive(Clone, Debug)]
pub struct Route {
    /// Points from the agent to where it stopped (m).
    pub points: Vec<Vec2>,
    /// Whether it ended within a cell of the goal.
    pub reached: bool,
}

/// How a heat-map block is shown.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum Heat {
    /// Most of its cells are blocked.
    Blocked,
    /// No path from it to the goal.
    Unreachable,
    /// Colour level `0..HEAT_LEVELS`.
    Level(usize),
}

/// The computed picture: field, agents and routes.
pub struct Picture {
    grid: Grid,
    /// Cells agents cannot enter: obstacles at `t`, and cells whose centre lies
    /// outside the bounds.
    blocked: Vec<bool>,
    phi: Vec<f64>,
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

/// `n` agents on a lattice over `start` (columns and rows in about the rectangle's
/// aspect), skipping positions in blocked cells; the lattice is refined until
/// `n` fit or it has 16 times as many points as asked. Row-major order.
pub fn sample_agents(start: Rect, n: usize, grid: &Grid, blocked: &[bool]) -> Vec<Vec2> {
    if n == 0 {
        return Vec::new();
    }
    let (w, h) = (start.width().max(1e-9), start.height().max(1e-9));
    let mut cols = ((n as f64 * w / h).sqrt().ceil() as usize).max(1);
    let mut best = Vec::new();
    loop {
        let rows = n.div_ceil(cols).max(1);
        let mut pts = Vec::with_capacity(cols * rows);
        for r in 0..rows {
            for c in 0..cols {
                let p = Vec2::new(
                    start.min[0] + (c as f64 + 0.5) / cols as f64 * w,
                    start.min[1] + (r as f64 + 0.5) / rows as f64 * h,
                );
                if grid.cell_of(p).is_some_and(|i| !blocked[i]) {
                    pts.push(p);
                }
            }
        }
        if pts.len() > best.len() {
            best = pts;
        }
        if best.len() >= n || cols * rows >= 16 * n {
            break;
        }
        cols += 1;
    }
    best.truncate(n);
    best
}

/// Descends `Φ` from `p` in steps of [`ROUTE_STEP_CELLS`] cells until within one
/// cell of `goal`, no descent direction is left, or the step budget runs out.
pub fn trace_route(grid: &Grid, phi: &[f64], p: Vec2, goal: Vec2) -> Route {
    let h = grid.cell_m();
    let step = ROUTE_STEP_CELLS * h;
    let budget = ROUTE_STEPS_PER_CELL * (grid.cols() + grid.rows());
    let mut points = vec![p];
    let mut q = p;
    for _ in 0..budget {
        if (q - goal).norm() <= h {
            points.push(goal);
            return Route {
                points,
                reached: true,
            };
        }
        match descent_direction(grid, phi, q) {
            Some(d) => {
                q += d * step;
                points.push(q);
            }
            None => break,
        }
    }
    let reached = (q - goal).norm() <= h;
    if reached {
        points.push(goal);
    }
    Route { points, reached }
}

/// Douglas–Peucker: the points of `pts` to keep so that no dropped point is more
/// than `tol` from the kept polyline. Always keeps the ends.
pub fn simplify(pts: &[Vec2], tol: f64) -> Vec<Vec2> {
    if pts.len() <= 2 {
        return pts.to_vec();
    }
    let mut keep = vec![false; pts.len()];
    keep[0] = true;
    keep[pts.len() - 1] = true;
    let mut stack = vec![(0, pts.len() - 1)];
    while let Some((a, b)) = stack.pop() {
        let (pa, pb) = (pts[a], pts[b]);
        let d = pb - pa;
        let len = d.norm();
        let mut far = (0.0, a);
        for (i, &p) in pts.iter().enumerate().take(b).skip(a + 1) {
            let dist = if len > 0.0 {
                (d.x * (p.y - pa.y) - d.y * (p.x - pa.x)).abs() / len
            } else {
                (p - pa).norm()
            };
            if dist > far.0 {
                far = (dist, i);
            }
        }
        if far.0 > tol {
            keep[far.1] = true;
            stack.push((a, far.1));
            stack.push((far.1, b));
        }
    }
    pts.iter()
        .zip(&keep)
        .filter(|(_, &k)| k)
        .map(|(&p, _)| p)
        .collect()
}

/// A step of 1, 2 or 5 × 10ⁿ giving at most `max_ticks` intervals up to `max`.
pub fn nice_step(max: f64, max_ticks: usize) -> f64 {
    if !(max.is_finite() && max > 0.0) {
        return 1.0;
    }
    let raw = max / max_ticks.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0] {
        if m * mag >= raw {
            return m * mag;
        }
    }
    10.0 * mag
}

/// The heat ramp at `u ∈ [0, 1]`: near-white (at the goal) through yellow and
/// orange to dark red (far), as mesh-formation-control Fig. 6.
pub fn ramp(u: f64) -> String {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [255.0, 252.0, 235.0]),
        (0.25, [253.0, 219.0, 140.0]),
        (0.5, [252.0, 146.0, 84.0]),
        (0.75, [215.0, 48.0, 31.0]),
        (1.0, [127.0, 0.0, 0.0]),
    ];
    let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) };
    let k = STOPS
        .iter()
        .position(|s| s.0 >= u)
        .unwrap_or(STOPS.len() - 1)
        .max(1);
    let ((u0, c0), (u1, c1)) = (STOPS[k - 1], STOPS[k]);
    let f = ((u - u0) / (u1 - u0)).clamp(0.0, 1.0);
    let ch = |i: usize| (c0[i] + (c1[i] - c0[i]) * f).round() as u8;
    format!("#{:02x}{:02x}{:02x}", ch(0), ch(1), ch(2))
}

/// Colour of a motion type's patches.
pub fn motion_colour(m: MotionType) -> &'static str {
    match m {
        MotionType::Run => "#7a7a7a",
        MotionType::Crawl => "#8c510a",
        MotionType::Duck => "#1b7837",
        MotionType::Swim => "#2166ac",
        MotionType::Jump => "#c51b7d",
        MotionType::ClimbUp => "#5e3c99",
        MotionType::ClimbDown => "#01857a",
    }
}

fn motion_label(m: MotionType) -> &'static str {
    match m {
        MotionType::Run => "run",
        MotionType::Crawl => "crawl",
        MotionType::Duck => "duck",
        MotionType::Swim => "swim",
        MotionType::Jump => "jump",
        MotionType::ClimbUp => "climb up",
        MotionType::ClimbDown => "climb down",
    }
}

const BLOCKED_FILL: &str = "#9c9c9c";
const UNREACHABLE_FILL: &str = "#d9d4e6";
const OBSTACLE_FILL: &str = "#4d4d4d";
const MOVING_FILL: &str = "#3f5a8c";
const CHECKPOINT_STROKE: &str = "#008b8b";
const ROUTE_STROKE: &str = "#1d3f7a";

/// Marching squares over a lattice of values (`+inf` = no value): the segments of
/// the iso-line at `level`, in lattice coordinates (corner `(i, j)` at `(i, j)`).
pub fn iso_segments(vals: &[f64], nx: usize, ny: usize, level: f64) -> Vec<[(f64, f64); 2]> {
    let mut out = Vec::new();
    if nx < 2 || ny < 2 {
        return out;
    }
    let at = |i: usize, j: usize| vals[j * nx + i];
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            // Corners a (i, j), b (i+1, j), c (i+1, j+1), d (i, j+1).
            let v = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            if v.iter().any(|x| !x.is_finite()) {
                continue;
            }
            let pos = [
                (i as f64, j as f64),
                (i as f64 + 1.0, j as f64),
                (i as f64 + 1.0, j as f64 + 1.0),
                (i as f64, j as f64 + 1.0),
            ];
            let below = v.map(|x| x < level);
            // Edge k joins corners k and k+1: 0 top, 1 right, 2 bottom, 3 left.
            let cross = |k: usize| -> Option<(f64, f64)> {
                let (a, b) = (k, (k + 1) % 4);
                if below[a] == below[b] {
                    return None;
                }
                let f = ((level - v[a]) / (v[b] - v[a])).clamp(0.0, 1.0);
                Some((
                    pos[a].0 + (pos[b].0 - pos[a].0) * f,
                    pos[a].1 + (pos[b].1 - pos[a].1) * f,
                ))
            };
            let e: Vec<(usize, (f64, f64))> =
                (0..4).filter_map(|k| cross(k).map(|p| (k, p))).collect();
            match e.len() {
                2 => out.push([e[0].1, e[1].1]),
                4 => {
                    let centre_below = (v.iter().sum::<f64>() / 4.0) < level;
                    let p = |k: usize| e[k].1;
                    if centre_below == below[0] {
                        // a and c connect through the centre: cut off b and d.
                        out.push([p(0), p(1)]);
                        out.push([p(2), p(3)]);
                    } else {
                        out.push([p(3), p(0)]);
                        out.push([p(1), p(2)]);
                    }
                }
                _ => {}
            }
        }
    }
    out
}

/// World to picture coordinates.
#[derive(Copy, Clone)]
struct View {
    bounds: Rect,
    px_per_m: f64,
    x0: f64,
    y0: f64,
}

impl View {
    fn x(&self, x: f64) -> f64 {
        self.x0 + (x - self.bounds.min[0]) * self.px_per_m
    }
    fn y(&self, y: f64) -> f64 {
        self.y0 + (y - self.bounds.min[1]) * self.px_per_m
    }
    fn pt(&self, p: Vec2) -> String {
        format!("{:.1},{:.1}", self.x(p.x), self.y(p.y))
    }
    fn w(&self) -> f64 {
        self.bounds.width() * self.px_per_m
    }
    fn h(&self) -> f64 {
        self.bounds.height() * self.px_per_m
    }
}

/// Writes one part (at `pl`) with the given attributes.
fn part_svg(s: &mut String, v: &View, part: &Part, pl: &Placement, class: &str, attrs: &str) {
    match part {
        Part::Polygon(poly) => {
            let pts: Vec<String> = poly
                .vertices()
                .iter()
                .map(|&p| v.pt(pl.to_world(p)))
                .collect();
            let _ = writeln!(
                s,
                r#"<polygon class="{class}" points="{}" {attrs}/>"#,
                pts.join(" ")
            );
        }
        Part::Circle(c) => {
            let p = pl.to_world(c.centre);
            let _ = writeln!(
                s,
                r#"<circle class="{class}" cx="{:.1}" cy="{:.1}" r="{:.1}" {attrs}/>"#,
                v.x(p.x),
                v.y(p.y),
                c.radius_m * v.px_per_m
            );
        }
    }
}

/// XML text escaping (also safe in attribute values).
pub fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A pixel coordinate with one decimal, without a trailing `.0`.
fn f1(x: f64) -> String {
    let s = format!("{x:.1}");
    match s.strip_suffix(".0") {
        Some("-0") => "0".into(),
        Some(t) => t.into(),
        None => s,
    }
}

/// A number without trailing zeros (at most 3 decimals).
fn num(x: f64) -> String {
    let s = format!("{x:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

impl Picture {
    /// Heat-map blocks: `(factor, nx, ny, class per block, Φ at block centres)`.
    fn heat_blocks(&self, bounds: Rect, vmax: f64) -> (usize, usize, usize, Vec<Heat>, Vec<f64>) {
        let g = &self.grid;
        let f = g
            .cols()
            .div_ceil(MAX_HEAT_COLS)
            .max(g.rows().div_ceil(MAX_HEAT_ROWS))
            .max(1);
        let (nx, ny) = (g.cols().div_ceil(f), g.rows().div_ceil(f));
        let mut heat = Vec::with_capacity(nx * ny);
        let mut vals = Vec::with_capacity(nx * ny);
        for bj in 0..ny {
            for bi in 0..nx {
                let (c0, c1) = (bi * f, ((bi + 1) * f).min(g.cols()));
                let (r0, r1) = (bj * f, ((bj + 1) * f).min(g.rows()));
                let (mut inside, mut blocked) = (0usize, 0usize);
                for r in r0..r1 {
                    for c in c0..c1 {
                        let i = g.index(c, r);
                        if bounds.contains(g.center(i)) {
                            inside += 1;
                            blocked += usize::from(self.blocked[i]);
                        }
                    }
                }
                let centre = self.block_centre(bounds, f, bi, bj);
                let v = sample(g, &self.phi, centre);
                let h = if inside == 0 || 2 * blocked > inside {
                    Heat::Blocked
                } else if !v.is_finite() {
                    Heat::Unreachable
                } else {
                    Heat::Level(((v / vmax * HEAT_LEVELS as f64) as usize).min(HEAT_LEVELS - 1))
                };
                vals.push(if matches!(h, Heat::Level(_)) {
                    v
                } else {
                    f64::INFINITY
                });
                heat.push(h);
            }
        }
        (f, nx, ny, heat, vals)
    }

    /// World rectangle of heat block `(bi, bj)`, clipped to the bounds.
    fn block_rect(&self, bounds: Rect, f: usize, bi: usize, bj: usize) -> Rect {
        let g = &self.grid;
        let s = g.cell_m() * f as f64;
        let o = g.origin();
        Rect {
            min: [
                (o.x + bi as f64 * s).max(bounds.min[0]),
                (o.y + bj as f64 * s).max(bounds.min[1]),
            ],
            max: [
                (o.x + (bi + 1) as f64 * s).min(bounds.max[0]),
                (o.y + (bj + 1) as f64 * s).min(bounds.max[1]),
            ],
        }
    }

    fn block_centre(&self, bounds: Rect, f: usize, bi: usize, bj: usize) -> Vec2 {
        self.block_rect(bounds, f, bi, bj).center()
    }

    /// The SVG document.
    pub fn svg(&self, scene: &Scene, o: &Options) -> String {
        let b = scene.bounds();
        let px_per_m = (MAP_W_PX / b.width()).min(MAP_H_PX / b.height());
        let v = View {
            bounds: b,
            px_per_m,
            x0: MARGIN_PX,
            y0: TITLE_PX,
        };
        let width = MARGIN_PX + v.w() + MARGIN_PX + PANEL_PX;
        let height = (TITLE_PX + v.h() + FOOTER_PX).max(TITLE_PX + 560.0);
        let step = nice_step(self.phi_max, 8);
        let vmax = (self.phi_max / step).ceil().max(1.0) * step;
        let mut s = String::with_capacity(1 << 17);
        let _ = writeln!(
            s,
            r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {width:.0} {height:.0}" width="{width:.0}" height="{height:.0}" font-family="sans-serif">"##
        );
        let _ = writeln!(
            s,
            r##"<defs><pattern id="unreachable" width="6" height="6" patternUnits="userSpaceOnUse"><rect width="6" height="6" fill="{UNREACHABLE_FILL}"/><path d="M0,6 L6,0" stroke="#8a7fa8" stroke-width="0.8"/></pattern><clipPath id="world"><rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}"/></clipPath></defs>"##,
            v.x0,
            v.y0,
            v.w(),
            v.h()
        );
        let _ = writeln!(
            s,
            r##"<rect x="0" y="0" width="{width:.0}" height="{height:.0}" fill="#fbfbf8"/>"##
        );
        // Title.
        let (gx, gy) = (self.goal.x, self.goal.y);
        let _ = writeln!(
            s,
            r##"<text class="title" x="{MARGIN_PX:.0}" y="19" font-size="15" fill="#222">{}: grid {} × {} cells of {} m, goal ({:.2}, {:.2}), t = {} s, {} agents</text>"##,
            xml_escape(scene.name()),
            self.grid.cols(),
            self.grid.rows(),
            num(self.grid.cell_m()),
            gx,
            gy,
            num(o.t_s),
            self.agents.len()
        );
        let _ = writeln!(
            s,
            r##"<text x="{MARGIN_PX:.0}" y="37" font-size="11.5" fill="#555">Φ: fast-marching travel time to the goal at {} m/s (eq. 7 with travel-speed patches); routes descend Φ</text>"##,
            num(o.preferred_speed_m_s)
        );

        // Heat map: runs of equal blocks along rows, one path per colour.
        let (f, nx, ny, heat, vals) = self.heat_blocks(b, vmax);
        let mut by_fill: std::collections::BTreeMap<String, String> = Default::default();
        for bj in 0..ny {
            let mut bi = 0;
            while bi < nx {
                let h = heat[bj * nx + bi];
                let mut end = bi + 1;
                while end < nx && heat[bj * nx + end] == h {
                    end += 1;
                }
                let r0 = self.block_rect(b, f, bi, bj);
                let r1 = self.block_rect(b, f, end - 1, bj);
                let fill = match h {
                    Heat::Blocked => BLOCKED_FILL.to_string(),
                    Heat::Unreachable => "url(#unreachable)".to_string(),
                    Heat::Level(l) => ramp((l as f64 + 0.5) / HEAT_LEVELS as f64),
                };
                let (x0, x1) = (v.x(r0.min[0]), v.x(r1.max[0]));
                let (y0, y1) = (v.y(r0.min[1]), v.y(r0.max[1]));
                if x1 > x0 && y1 > y0 {
                    let d = by_fill.entry(fill).or_default();
                    let _ = write!(
                        d,
                        "M{} {}h{}v{}h-{}z",
                        f1(x0),
                        f1(y0),
                        f1(x1 - x0),
                        f1(y1 - y0),
                        f1(x1 - x0)
                    );
                }
                bi = end;
            }
        }
        s.push_str(r#"<g class="heatmap" shape-rendering="crispEdges">"#);
        s.push('\n');
        for (fill, d) in &by_fill {
            let _ = writeln!(s, r#"<path class="heat" fill="{fill}" d="{d}"/>"#);
        }
        s.push_str("</g>\n");

        // Iso-time contours on the block-centre lattice.
        s.push_str(r##"<g class="contours" fill="none" stroke="#5a1a00" stroke-opacity="0.45" stroke-width="0.7" clip-path="url(#world)">"##);
        s.push('\n');
        let levels = (vmax / step).round() as usize;
        for k in 1..levels {
            let level = k as f64 * step;
            let segs = iso_segments(&vals, nx, ny, level);
            if segs.is_empty() {
                continue;
            }
            let to_px = |(i, j): (f64, f64)| {
                let c = self.block_centre(b, f, 0, 0);
                let sz = self.grid.cell_m() * f as f64;
                (v.x(c.x + i * sz), v.y(c.y + j * sz))
            };
            let mut d = String::new();
            for [p, q] in segs {
                let (p, q) = (to_px(p), to_px(q));
                let _ = write!(d, "M{:.1},{:.1}L{:.1},{:.1}", p.0, p.1, q.0, q.1);
            }
            let _ = writeln!(
                s,
                r#"<path class="contour" data-s="{}" d="{d}"/>"#,
                num(level)
            );
        }
        s.push_str("</g>\n");

        // Bounds.
        let _ = writeln!(
            s,
            r##"<rect class="bounds" x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#222" stroke-width="1.5"/>"##,
            v.x0,
            v.y0,
            v.w(),
            v.h()
        );

        // Static patches, then moving patches, in file order (the last one wins).
        for p in scene.patches() {
            let c = motion_colour(p.terrain.motion);
            let _ = writeln!(
                s,
                "<g><title>{} ({} ×{})</title>",
                xml_escape(&p.name),
                motion_label(p.terrain.motion),
                num(p.terrain.speed_factor)
            );
            for part in &p.parts {
                part_svg(
                    &mut s,
                    &v,
                    part,
                    &Placement::IDENTITY,
                    "patch",
                    &format!(r#"fill="{c}" fill-opacity="0.22" stroke="{c}" stroke-width="1.5""#),
                );
            }
            s.push_str("</g>\n");
        }

        // Static obstacles.
        for ob in scene.obstacles() {
            let _ = writeln!(s, "<g><title>{}</title>", xml_escape(&ob.name));
            for part in &ob.parts {
                part_svg(
                    &mut s,
                    &v,
                    part,
                    &Placement::IDENTITY,
                    "obstacle",
                    &format!(r##"fill="{OBSTACLE_FILL}" stroke="#1a1a1a" stroke-width="1""##),
                );
            }
            s.push_str("</g>\n");
        }

        // Moving things: the path dashed, the parts where they are at t.
        for d in scene.dynamic() {
            // A ping-pong traversal retraces its way back: draw the way out only.
            let all = d.path.points();
            let shown = match d.path.mode() {
                PathMode::PingPong => &all[..all.len().div_ceil(2)],
                PathMode::Looped => all,
            };
            let pts: Vec<String> = shown.iter().map(|&p| v.pt(p)).collect();
            let (class, fill, attrs) = match d.kind {
                DynamicKind::Obstacle => (
                    "moving-obstacle",
                    MOVING_FILL,
                    format!(
                        r##"fill="{MOVING_FILL}" fill-opacity="0.9" stroke="#1a1a1a" stroke-width="1""##
                    ),
                ),
                DynamicKind::Patch(t) => {
                    let c = motion_colour(t.motion);
                    (
                        "moving-patch",
                        c,
                        format!(r#"fill="{c}" fill-opacity="0.3" stroke="{c}" stroke-width="1.5""#),
                    )
                }
            };
            let _ = writeln!(
                s,
                "<g><title>{} at t = {} s</title>",
                xml_escape(&d.name),
                num(o.t_s)
            );
            let _ = writeln!(
                s,
                r#"<polyline class="path" points="{}" fill="none" stroke="{fill}" stroke-width="1.3" stroke-dasharray="6 4"/>"#,
                pts.join(" ")
            );
            let pl = d.placement_at(o.t_s);
            for part in &d.parts {
                part_svg(&mut s, &v, part, &pl, class, &attrs);
            }
            s.push_str("</g>\n");
        }

        // Checkpoints, outlined, with their formation names.
        for c in scene.checkpoints() {
            let _ = writeln!(
                s,
                "<g><title>checkpoint {}: formation {}</title>",
                xml_escape(&c.name),
                xml_escape(&c.formation)
            );
            part_svg(
                &mut s,
                &v,
                &c.region,
                &Placement::IDENTITY,
                "checkpoint",
                &format!(
                    r#"fill="none" stroke="{CHECKPOINT_STROKE}" stroke-width="2" stroke-dasharray="2 2""#
                ),
            );
            let p = c.region.centre();
            let _ = writeln!(
                s,
                r##"<text class="formation" x="{:.1}" y="{:.1}" font-size="12" font-weight="bold" text-anchor="middle" fill="{CHECKPOINT_STROKE}" stroke="#fbfbf8" stroke-width="3" paint-order="stroke">{}</text>"##,
                v.x(p.x),
                v.y(p.y) + 4.0,
                xml_escape(&c.formation)
            );
            s.push_str("</g>\n");
        }

        // Routes and agents.
        let tol_m = ROUTE_TOLERANCE_PX / px_per_m;
        s.push_str(&format!(
            r#"<g fill="none" stroke="{ROUTE_STROKE}" stroke-width="1.1" stroke-opacity="0.75" stroke-linejoin="round">"#
        ));
        s.push('\n');
        for r in &self.routes {
            let pts: Vec<String> = simplify(&r.points, tol_m)
                .into_iter()
                .map(|p| v.pt(p))
                .collect();
            let extra = if r.reached {
                ""
            } else {
                r#" stroke-dasharray="3 2""#
            };
            let _ = writeln!(
                s,
                r#"<polyline class="route" points="{}"{extra}/>"#,
                pts.join(" ")
            );
        }
        s.push_str("</g>\n");
        for &a in &self.agents {
            let reachable = sample(&self.grid, &self.phi, a).is_finite();
            let fill = if reachable { "#ffffff" } else { "#d33" };
            let _ = writeln!(
                s,
                r#"<circle class="agent" cx="{:.1}" cy="{:.1}" r="2.6" fill="{fill}" stroke="{ROUTE_STROKE}" stroke-width="1"/>"#,
                v.x(a.x),
                v.y(a.y)
            );
        }
        // Goal: a ringed cross.
        let (gx, gy) = (v.x(self.goal.x), v.y(self.goal.y));
        let _ = writeln!(
            s,
            r##"<g class="goal" stroke="#000" stroke-width="2" fill="none"><circle cx="{gx:.1}" cy="{gy:.1}" r="7" fill="#ffffff" fill-opacity="0.7"/><path d="M{:.1},{gy:.1}H{:.1}M{gx:.1},{:.1}V{:.1}"/></g>"##,
            gx - 11.0,
            gx + 11.0,
            gy - 11.0,
            gy + 11.0
        );

        self.scale_bar(&mut s, &v);
        self.legend(&mut s, scene, &v, o, step, vmax);
        s.push_str("</svg>\n");
        s
    }

    fn scale_bar(&self, s: &mut String, v: &View) {
        let len_m = nice_step(v.bounds.width() / 4.0, 1);
        let units = [len_m / 2.0, len_m / 2.0];
        let (x, y) = (v.x0, v.y0 + v.h() + 18.0);
        let _ = writeln!(s, r##"<g class="scale-bar" font-size="11" fill="#222">"##);
        let mut at = x;
        for (k, u) in units.iter().enumerate() {
            let w = u * v.px_per_m;
            let fill = if k % 2 == 0 { "#222" } else { "#fbfbf8" };
            let _ = writeln!(
                s,
                r##"<rect x="{at:.1}" y="{y:.1}" width="{w:.1}" height="6" fill="{fill}" stroke="#222" stroke-width="1"/>"##
            );
            at += w;
        }
        let _ = writeln!(
            s,
            r#"<text x="{x:.1}" y="{:.1}">0</text><text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text><text x="{at:.1}" y="{:.1}" text-anchor="end">{} m</text>"#,
            y + 19.0,
            x + units[0] * v.px_per_m,
            y + 19.0,
            num(len_m / 2.0),
            y + 19.0,
            num(len_m)
        );
        s.push_str("</g>\n");
    }

    fn legend(&self, s: &mut String, scene: &Scene, v: &View, o: &Options, step: f64, vmax: f64) {
        let x = v.x0 + v.w() + MARGIN_PX + 6.0;
        let mut y = v.y0 + 4.0;
        let _ = writeln!(s, r##"<g class="legend" font-size="11.5" fill="#222">"##);
        let _ = writeln!(
            s,
            r#"<text x="{x:.1}" y="{:.1}" font-weight="bold">Travel speed × running</text>"#,
            y + 8.0
        );
        y += 16.0;
        for m in MotionType::ALL {
            let c = motion_colour(m);
            let mut factors: Vec<f64> = scene
                .patches()
                .iter()
                .map(|p| p.terrain)
                .chain(scene.dynamic().iter().filter_map(|d| match d.kind {
                    DynamicKind::Patch(t) => Some(t),
                    DynamicKind::Obstacle => None,
                }))
                .filter(|t| t.motion == m && t.speed_factor != m.default_speed_factor())
                .map(|t| t.speed_factor)
                .collect();
            factors.sort_by(f64::total_cmp);
            factors.dedup();
            let mut label = format!("{} ×{:.2}", motion_label(m), m.default_speed_factor());
            if !factors.is_empty() {
                let f: Vec<String> = factors.iter().map(|f| format!("×{}", num(*f))).collect();
                let _ = write!(label, " (here {})", f.join(", "));
            }
            let _ = writeln!(
                s,
                r#"<rect class="legend-motion" x="{x:.1}" y="{y:.1}" width="16" height="11" fill="{c}" fill-opacity="0.22" stroke="{c}" stroke-width="1.5"/><text x="{:.1}" y="{:.1}">{}</text>"#,
                x + 22.0,
                y + 9.5,
                xml_escape(&label)
            );
            y += 16.0;
        }
        y += 10.0;
        let swatch = |s: &mut String, y: f64, attrs: &str, label: &str| {
            let _ = writeln!(
                s,
                r#"<rect x="{x:.1}" y="{y:.1}" width="16" height="11" {attrs}/><text x="{:.1}" y="{:.1}">{label}</text>"#,
                x + 22.0,
                y + 9.5
            );
        };
        swatch(
            s,
            y,
            &format!(r##"fill="{OBSTACLE_FILL}" stroke="#1a1a1a""##),
            "obstacle",
        );
        y += 16.0;
        swatch(
            s,
            y,
            &format!(r##"fill="{MOVING_FILL}" stroke="#1a1a1a""##),
            &format!("moving, at t = {} s (path dashed)", num(o.t_s)),
        );
        y += 16.0;
        swatch(
            s,
            y,
            &format!(
                r#"fill="none" stroke="{CHECKPOINT_STROKE}" stroke-width="2" stroke-dasharray="2 2""#
            ),
            "checkpoint: formation",
        );
        y += 16.0;
        swatch(s, y, &format!(r#"fill="{BLOCKED_FILL}""#), "blocked cell");
        y += 16.0;
        swatch(
            s,
            y,
            r##"fill="url(#unreachable)" stroke="#8a7fa8" stroke-width="0.5""##,
            "unreachable cell",
        );
        y += 16.0;
        let _ = writeln!(
            s,
            r##"<circle cx="{:.1}" cy="{:.1}" r="2.6" fill="#ffffff" stroke="{ROUTE_STROKE}"/><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{ROUTE_STROKE}" stroke-width="1.1"/><text x="{:.1}" y="{:.1}">agent and its route</text>"##,
            x + 3.0,
            y + 5.5,
            x + 5.6,
            y + 5.5,
            x + 16.0,
            y + 5.5,
            x + 22.0,
            y + 9.5
        );
        y += 16.0;
        let _ = writeln!(
            s,
            r##"<circle cx="{:.1}" cy="{:.1}" r="5" fill="none" stroke="#000" stroke-width="1.6"/><text x="{:.1}" y="{:.1}">goal</text>"##,
            x + 8.0,
            y + 5.5,
            x + 22.0,
            y + 9.5
        );
        y += 26.0;

        // Colour scale: one band per heat level, ticks every contour step.
        let _ = writeln!(
            s,
            r#"<text x="{x:.1}" y="{:.1}" font-weight="bold">Φ: travel time to goal (s)</text>"#,
            y
        );
        let _ = writeln!(
            s,
            r##"<text x="{x:.1}" y="{:.1}" font-size="10.5" fill="#555">at {} m/s; contours every {} s</text>"##,
            y + 14.0,
            num(o.preferred_speed_m_s),
            num(step)
        );
        y += 22.0;
        let bar_h = (v.y0 + v.h() - y - 8.0).clamp(80.0, 200.0);
        let band = bar_h / HEAT_LEVELS as f64;
        s.push_str(r#"<g class="colour-scale" shape-rendering="crispEdges">"#);
        for l in 0..HEAT_LEVELS {
            let _ = write!(
                s,
                r#"<rect x="{x:.1}" y="{:.2}" width="18" height="{:.2}" fill="{}"/>"#,
                y + l as f64 * band,
                band + 0.05,
                ramp((l as f64 + 0.5) / HEAT_LEVELS as f64)
            );
        }
        s.push_str("</g>\n");
        let _ = writeln!(
            s,
            r##"<rect x="{x:.1}" y="{y:.1}" width="18" height="{bar_h:.1}" fill="none" stroke="#222" stroke-width="0.8"/>"##
        );
        let ticks = (vmax / step).round() as usize;
        for k in 0..=ticks {
            let ty = y + bar_h * (k as f64 * step / vmax);
            let _ = writeln!(
                s,
                r##"<line x1="{:.1}" y1="{ty:.1}" x2="{:.1}" y2="{ty:.1}" stroke="#222"/><text x="{:.1}" y="{:.1}" font-size="10.5">{} s</text>"##,
                x + 18.0,
                x + 22.0,
                x + 25.0,
                ty + 3.5,
                num(k as f64 * step)
            );
        }
        s.push_str("</g>\n");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_point_accepts_x_comma_y_and_rejects_the_rest() {
        assert_eq!(parse_point("14.5,4.5"), Ok([14.5, 4.5]));
        assert_eq!(parse_point(" -1 , 2 "), Ok([-1.0, 2.0]));
        for bad in ["", "1", "1,", "a,2", "1,2,3", "nan,1", "inf,0"] {
            assert!(parse_point(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn nice_steps_are_1_2_5() {
        assert_eq!(nice_step(10.0, 8), 2.0);
        assert_eq!(nice_step(8.0, 8), 1.0);
        assert_eq!(nice_step(0.9, 8), 0.2);
        assert_eq!(nice_step(35.0, 8), 5.0);
        assert_eq!(nice_step(16.0 / 4.0, 1), 5.0);
        assert_eq!(nice_step(f64::NAN, 8), 1.0);
    }

    #[test]
    fn ramp_runs_from_near_white_to_dark_red() {
        assert_eq!(ramp(0.0), "#fffceb");
        assert_eq!(ramp(1.0), "#7f0000");
        assert_eq!(ramp(-1.0), ramp(0.0));
        assert_eq!(ramp(f64::NAN), ramp(0.0));
        assert_eq!(ramp(0.5), "#fc9254");
    }

    #[test]
    fn simplify_keeps_corners_and_drops_collinear_points() {
        let pts: Vec<Vec2> = (0..=10)
            .map(|i| Vec2::new(i as f64, 0.0))
            .chain((1..=10).map(|i| Vec2::new(10.0, i as f64)))
            .collect();
        let s = simplify(&pts, 0.01);
        assert_eq!(
            s,
            [
                Vec2::new(0.0, 0.0),
                Vec2::new(10.0, 0.0),
                Vec2::new(10.0, 10.0)
            ]
        );
        assert_eq!(simplify(&pts[..2], 0.01), &pts[..2]);
    }

    #[test]
    fn iso_segments_of_a_plane_are_one_straight_line() {
        // v = x on a 3 × 3 lattice: the level 0.5 is the line x = 0.5.
        let vals = [0.0, 1.0, 2.0, 0.0, 1.0, 2.0, 0.0, 1.0, 2.0];
        let segs = iso_segments(&vals, 3, 3, 0.5);
        assert_eq!(segs.len(), 2);
        for s in segs {
            assert!((s[0].0 - 0.5).abs() < 1e-12 && (s[1].0 - 0.5).abs() < 1e-12);
        }
        // A missing corner drops the squares around it.
        let mut holes = vals;
        holes[3] = f64::INFINITY;
        assert!(iso_segments(&holes, 3, 3, 0.5).is_empty());
    }

    #[test]
    fn agents_fill_the_start_and_skip_blocked_cells() {
        let grid = Grid::new(16, 9, 1.0, Vec2::zeros()).unwrap();
        let mut blocked = vec![false; grid.len()];
        let start = Rect {
            min: [6.0, 3.0],
            max: [10.0, 6.0],
        };
        let a = sample_agents(start, 40, &grid, &blocked);
        assert_eq!(a.len(), 40);
        assert!(a.iter().all(|p| start.contains(*p)));
        // Block the start's west half: still 40, none in it.
        for r in 3..6 {
            for c in 6..8 {
                blocked[grid.index(c, r)] = true;
            }
        }
        let b = sample_agents(start, 40, &grid, &blocked);
        assert_eq!(b.len(), 40);
        assert!(b.iter().all(|p| p.x >= 8.0));
        assert!(sample_agents(start, 0, &grid, &blocked).is_empty());
    }
}
