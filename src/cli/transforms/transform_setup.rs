//! The start of a `crowdtouch transform` run, set up as the daemon sets one up
//! (`engine/transform.rs::request_transform`): the config's transform settings,
//! the formations named or read from files, where they are laid out, the agents
//! sampled in the source (formation-transform section 3.1).

use super::shared::Common;
use anyhow::{anyhow, bail, Context, Result};
use crowdtouch::config::{Config, MAX_AGENTS};
use crowdtouch::crowd::formation::{
    hex_fit, BitmapDef, Formation, FormationDef, FormationLibrary, Placement, SampleParams, START,
};
use crowdtouch::crowd::transform::{ApParams, MoveParams, PairCost, TransformRequest};
use crowdtouch::geom::Vec2;
use crowdtouch::located::{format_issues, locate_field, parse_strict, read_bytes, Issue};
use std::path::Path;
/// Share of the area the agents' hexagonal cells may fill before the area is
/// scaled up (a crowd packed tighter has no room to pass through itself).
pub const PACKING_SLACK: f64 = 0.6;
/// Targets are sampled at least this many agent radii apart (as the daemon's
/// `SAMPLE_SPACING_RADII`).
pub const SPACING_RADII: f64 = 2.0;
/// Relaxation iterations of the sampling (as the daemon's `SAMPLE_RELAX_ITERATIONS`).
pub const RELAX_ITERATIONS: u32 = 30;
/// A bare image file given as a formation: its pixels with every channel at most
/// this are the shape (eq. 1's `c_max`, `c_min` = black), as the shipped heart.
pub const BITMAP_DARK_MAX: u8 = 127;
/// Largest formation file read (bytes), as the config's bitmap cap.
pub const MAX_FORMATION_FILE_BYTES: u64 = 16 << 20;

/// The config's transform settings: what `engine/params.rs` (`pair_cost`,
/// `ap_params`, `move_params`) builds for the daemon, rebuilt here because the
/// engine does not export them.
#[derive(Clone, Debug)]
pub struct Settings {
    /// `formations.cost` with `formations.lambda`.
    pub cost: PairCost,
    /// `formations.subgroups`; `None` when off.
    pub ap: Option<ApParams>,
    /// `formations.transform` at the crowd's radius.
    pub moves: MoveParams,
}

impl Settings {
    /// The settings of `cfg` for agents of radius `radius_m`.
    pub fn of(cfg: &Config, radius_m: f64) -> Settings {
        use crowdtouch::engine::{ap_params, move_params, pair_cost};
        Settings {
            cost: pair_cost(cfg),
            ap: ap_params(cfg),
            moves: move_params(cfg, radius_m),
        }
    }
}

/// A transform's start: the config, both shapes, where they are laid out and the
/// agents sampled in the source.
pub struct Setup {
    /// The config.
    pub cfg: Config,
    /// As given on the command line.
    pub from_label: String,
    /// As given on the command line.
    pub to_label: String,
    /// The target shape.
    pub to: Formation,
    /// Agents.
    pub agents: usize,
    /// Agent radius (m).
    pub radius_m: f64,
    /// Where both shapes are laid out.
    pub place: Placement,
    /// Why the area is not `crowd.formation`'s, when it is not.
    pub area_note: Option<String>,
    /// How targets are sampled.
    pub sample: SampleParams,
    /// `s_i`: the agents, sampled in the source shape (m).
    pub sources: Vec<Vec2>,
    /// The seed given.
    pub seed: u64,
    /// The config's transform settings.
    pub settings: Settings,
}

impl Setup {
    /// Loads the config, resolves both formations and samples the agents in the
    /// source.
    ///
    /// # Errors
    /// An unreadable or invalid config, an unknown formation name (with the known
    /// ones), a formation file that cannot be read or is not valid (named), an
    /// agent count out of `1..=MAX_AGENTS`, more agents than fit in the source (the
    /// sampling's message).
    pub fn new(c: &Common) -> Result<Setup> {
        let cfg = match &c.config {
            Some(p) => Config::load(p)?,
            None => Config::embedded_default(),
        };
        let agents = c.agents.unwrap_or(cfg.crowd.agents);
        if !(1..=MAX_AGENTS).contains(&agents) {
            bail!("--agents must be 1 to {MAX_AGENTS}, got {agents}");
        }
        let agents = agents as usize;
        let (from_label, to_label) = (
            c.from.clone().unwrap_or_default(),
            c.to.clone().unwrap_or_default(),
        );
        let from = resolve(&cfg, &from_label).context("--from")?;
        let to = resolve(&cfg, &to_label).context("--to")?;
        let radius_m = cfg.crowd.agent_radius_m;
        let spacing_m = SPACING_RADII * radius_m;
        let rect = cfg.crowd.formation;
        let rect_area = rect.width() * rect.height();
        // Each agent takes a hexagonal cell of √3/2 · spacing² at the closest
        // packing; at most PACKING_SLACK of the area is filled.
        let needed = agents as f64 * 0.5 * 3f64.sqrt() * spacing_m * spacing_m / PACKING_SLACK;
        let (area_m2, area_note) = if needed > rect_area {
            (
                needed,
                Some(format!(
                    "{needed:.1} m², crowd.formation's {rect_area:.1} m² scaled up so that {agents} agents {spacing_m:.2} m apart fill at most {:.0} % of it (hex fit {})",
                    100.0 * PACKING_SLACK,
                    hex_fit(needed, spacing_m)
                )),
            )
        } else {
            (rect_area, None)
        };
        let place = Placement {
            centre_m: rect.center(),
            heading: Vec2::new(1.0, 0.0),
            area_m2,
        };
        let sample = SampleParams {
            min_spacing_m: spacing_m,
            relax_iterations: RELAX_ITERATIONS,
        };
        let sources = from
            .sample(&place, agents, &sample, source_seed(c.seed), &|| false)
            .map_err(|e| anyhow!("--from {from_label}: {e}"))?
            .ok_or_else(|| anyhow!("sampling the source was cancelled"))?;
        let settings = Settings::of(&cfg, radius_m);
        Ok(Setup {
            cfg,
            from_label,
            to_label,
            to,
            agents,
            radius_m,
            place,
            area_note,
            sample,
            sources,
            seed: c.seed,
            settings,
        })
    }

    /// The request the daemon's formation thread would prepare, for `cost` and
    /// subgroups `ap`.
    pub fn request(&self, cost: PairCost, ap: Option<ApParams>) -> TransformRequest {
        TransformRequest {
            name: self.to.name().to_string(),
            epoch: 0,
            formation: self.to.clone(),
            placement: self.place,
            agents: self.sources.clone(),
            cost,
            subgroups: ap,
            sample: self.sample,
            seed: target_seed(self.seed),
        }
    }

    /// Samples the target shape (as [`TransformRequest::prepare`] does with the
    /// same seed), so several pairings can share the targets.
    ///
    /// # Errors
    /// More agents than fit in the target.
    pub fn targets(&self) -> Result<Vec<Vec2>> {
        self.to
            .sample(
                &self.place,
                self.agents,
                &self.sample,
                target_seed(self.seed),
                &|| false,
            )
            .map_err(|e| anyhow!("--to {}: {e}", self.to_label))?
            .ok_or_else(|| anyhow!("sampling the target was cancelled"))
    }
}

/// Seed of the source sampling.
fn source_seed(seed: u64) -> u64 {
    seed ^ 0x5a3c_0f00_d15e_a5e5
}

/// Seed of the target sampling.
fn target_seed(seed: u64) -> u64 {
    seed ^ 0x7a5f_0e11
}

/// The formation `arg` names: a library name (`start`: the `crowd.formation`
/// rectangle) or a file.
///
/// # Errors
/// An unknown name (listing the known ones), a file that cannot be read or is not
/// a valid formation.
pub fn resolve(cfg: &Config, arg: &str) -> Result<Formation> {
    let lib: &FormationLibrary = cfg.formation_library();
    if arg == START {
        let def = FormationDef::rectangle("start rectangle", cfg.crowd.formation);
        return Formation::new(&def).map_err(|e| anyhow!("crowd.formation: {e}"));
    }
    if let Some(f) = lib.get(arg) {
        return Ok(f.clone());
    }
    let path = Path::new(arg);
    let looks_like_file = path.exists()
        || arg.contains('/')
        || matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("ron" | "png" | "pgm")
        );
    if !looks_like_file {
        bail!(
            "unknown formation `{arg}`: known formations are {}; or give a file (a polygon .ron, a .png or .pgm image)",
            lib.names_list()
        );
    }
    load_file(path)
}

/// A formation from a file: a PNG or PGM image (its dark pixels, scaled to the
/// crowd's area) or a polygon FormationDef in RON (a bitmap it names is read
/// relative to it).
///
/// # Errors
/// The file named, with what is wrong (and where, for RON).
pub fn load_file(path: &Path) -> Result<Formation> {
    let shown = path.display();
    let bytes = read_bytes(path, MAX_FORMATION_FILE_BYTES).map_err(|e| anyhow!("{e}"))?;
    if bytes.starts_with(b"\x89PNG") || bytes.starts_with(b"P2") || bytes.starts_with(b"P5") {
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("bitmap")
            .to_string();
        let def = BitmapDef {
            path: shown.to_string(),
            c_min: (0, 0, 0),
            c_max: (BITMAP_DARK_MAX, BITMAP_DARK_MAX, BITMAP_DARK_MAX),
            size_m: None,
        };
        return Formation::from_bitmap(&name, &bytes, &def).map_err(|e| anyhow!("{e}"));
    }
    let text = match String::from_utf8(bytes) {
        Ok(t) => t,
        Err(_) => bail!("{shown}: neither a PNG or PGM image nor a RON formation (not UTF-8 text)"),
    };
    let def: FormationDef =
        parse_strict(&text).map_err(|issue| anyhow!("{}", format_issues(path, &[issue])))?;
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let read = move |p: &str| -> Result<Vec<u8>, String> {
        read_bytes(&base.join(p), MAX_FORMATION_FILE_BYTES).map_err(|e| e.to_string())
    };
    Formation::from_def(&def, &read).map_err(|e| {
        let field = e.field();
        let (line, column) = locate_field(&text, field).unwrap_or((0, 0));
        let issue = Issue {
            field: field.to_string(),
            line,
            column,
            message: e.to_string(),
        };
        anyhow!("{}", format_issues(path, &[issue]))
    })
}
