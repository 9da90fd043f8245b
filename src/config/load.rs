//! Loading: the embedded default, files (size-capped), text, the search path; the
//! scene and the formation library are loaded and checked with the config.

use super::error::{ConfigIssue, Error};
use super::inputs::InputConfig;
use super::model::Config;
use crate::crowd::edit::io::{read_tracks, ReadOptions};
use crate::crowd::formation::FormationLibrary;
use crate::gesture::recognise::Recogniser;
use crate::located::{locate_field, parse_strict, read_bytes, read_text, ReadError};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// Largest config file read (bytes).
pub const MAX_CONFIG_BYTES: u64 = 1 << 20;

/// The embedded default config text (`config/crowdtouch.ron`).
pub const DEFAULT_CONFIG_RON: &str = include_str!("../../config/crowdtouch.ron");

impl Config {
    /// The embedded default (`config/crowdtouch.ron`).
    pub fn embedded_default() -> Config {
        match Config::from_str(DEFAULT_CONFIG_RON, Path::new("<embedded>")) {
            Ok(c) => c,
            // The shipped file is checked by tests; reaching this is a build defect.
            Err(e) => panic!("embedded default config is invalid: {e}"),
        }
    }

    /// Reads and validates a config file. Relative input paths are resolved against
    /// the file's directory.
    ///
    /// # Errors
    /// [`Error::Io`], [`Error::TooLarge`] or [`Error::Invalid`] with every problem.
    pub fn load(path: &Path) -> Result<Config, Error> {
        Config::load_with_text(path).map(|(cfg, _)| cfg)
    }

    /// [`Config::load`], also returning the text read, to place later findings
    /// about the config ([`locate_issues`]) in the same text.
    ///
    /// # Errors
    /// As [`Config::load`].
    pub fn load_with_text(path: &Path) -> Result<(Config, String), Error> {
        let text = read_text(path, MAX_CONFIG_BYTES).map_err(Error::from)?;
        let base = path.parent().unwrap_or(Path::new("."));
        Config::from_str_at(&text, path, base).map(|cfg| (cfg, text))
    }

    /// Parses and validates config text; `path` is used in messages only. Relative
    /// paths (recordings, the scene) stay relative to the working directory.
    ///
    /// # Errors
    /// [`Error::Invalid`] listing every problem with line, column and field.
    #[allow(clippy::should_implement_trait)]
    pub fn from_str(text: &str, path: &Path) -> Result<Config, Error> {
        Config::from_str_at(text, path, Path::new(""))
    }

    /// [`Config::from_str`] with relative paths resolved against `base`; the scene
    /// is loaded and validated (its problems are reported at the `scene` field).
    fn from_str_at(text: &str, path: &Path, base: &Path) -> Result<Config, Error> {
        let mut cfg: Config = parse_strict(text).map_err(|issue| Error::Invalid {
            path: path.to_path_buf(),
            issues: vec![issue],
        })?;
        let mut problems = cfg.validate();
        let read = |p: &str| read_image(&base.join(p));
        match FormationLibrary::with_files(&cfg.formations.shapes, &read) {
            Ok(lib) => cfg.library = Arc::new(lib),
            Err(e) => problems.extend(
                e.into_iter()
                    .map(|(f, m)| (format!("formations.shapes{f}"), m)),
            ),
        }
        if problems.is_empty() {
            cfg.resolve_paths(base);
            if let Some(scene_path) = &cfg.scene {
                match crate::crowd::environment::load_scene(scene_path, cfg.crowd.agent_radius_m)
                    .and_then(|s| {
                        s.check_formations(scene_path, &cfg.library.known_names())
                            .map(|()| s)
                    }) {
                    Ok(scene) => cfg.loaded_scene = Some(Arc::new(scene)),
                    Err(e) => {
                        problems.push(("scene".to_string(), format!("scene not usable:\n{e}")))
                    }
                }
            }
        }
        if problems.is_empty() {
            if let Some(edit) = &cfg.edit {
                if !(edit.threshold_m.is_finite()
                    && edit.threshold_m > 0.0
                    && edit.threshold_m <= 10.0)
                {
                    problems.push((
                        "edit.threshold_m".to_string(),
                        format!("must be in (0, 10] m, got {}", edit.threshold_m),
                    ));
                }
                if !edit.tracks.as_os_str().is_empty() {
                    match read_tracks(&edit.tracks, None, &ReadOptions::default()) {
                        Ok((set, _)) => cfg.loaded_tracks = Some(Arc::new(set)),
                        Err(e) => problems
                            .push(("edit.tracks".to_string(), format!("tracks not usable: {e}"))),
                    }
                }
            }
        }
        if problems.is_empty() {
            problems.extend(super::transform::check_gesture_formations(
                &cfg.formations.gestures,
                &cfg.library.known_names(),
            ));
        }
        if problems.is_empty() && cfg.gestures.enabled {
            match load_recogniser(
                cfg.gestures.library.as_deref(),
                cfg.gestures.band,
                cfg.gestures.collected,
            ) {
                Ok(r) => {
                    problems.extend(super::transform::check_gesture_classes(
                        &cfg.formations.gestures,
                        &cfg.gestures.disabled,
                        &r.library().classes,
                        r.source(),
                    ));
                    cfg.recogniser = Some(r);
                }
                Err(e) => problems.push((
                    "gestures.library".to_string(),
                    format!("gesture library not usable: {e}"),
                )),
            }
        }
        if problems.is_empty() {
            Ok(cfg)
        } else {
            Err(Error::Invalid {
                path: path.to_path_buf(),
                issues: locate_issues(text, problems),
            })
        }
    }

    fn resolve_paths(&mut self, base: &Path) {
        if let Some(s) = &mut self.scene {
            if s.is_relative() {
                *s = base.join(&*s);
            }
        }
        if let Some(e) = &mut self.edit {
            if e.tracks.is_relative() && !e.tracks.as_os_str().is_empty() {
                e.tracks = base.join(&e.tracks);
            }
            if let Some(d) = &mut e.dir {
                if d.is_relative() {
                    *d = base.join(&*d);
                }
            }
        }
        if let Some(l) = &mut self.gestures.library {
            if l.is_relative() {
                *l = base.join(&*l);
            }
        }
        for input in &mut self.inputs {
            match input {
                InputConfig::Replay { files, .. } => {
                    for f in files.iter_mut() {
                        if f.is_relative() {
                            *f = base.join(&*f);
                        }
                    }
                }
                InputConfig::Device { .. } | InputConfig::Tuio { .. } => {}
            }
        }
    }
}

/// Largest formation image read (bytes).
pub const MAX_IMAGE_BYTES: u64 = 16 << 20;

/// A formation bitmap's bytes (`formations.shapes[i].bitmap.path`, relative to the
/// config file's directory), at most [`MAX_IMAGE_BYTES`].
fn read_image(path: &Path) -> Result<Vec<u8>, String> {
    read_bytes(path, MAX_IMAGE_BYTES).map_err(|e| match e {
        ReadError::Io { source, .. } => format!("cannot read {}: {source}", path.display()),
        e => format!("cannot read {e}"),
    })
}

/// The gesture library at `path` (the shipped one for `None`), indexed for
/// recognition with DTW band `band`. The shipped library is read and indexed once
/// per process (every config shares it); a file is read on every load, so a
/// SIGHUP picks up a new library and a corrupt one is refused with the config,
/// leaving the running one in place.
///
/// # Errors
/// The file's read error or [`crate::gesture::library::LibraryError`], as text.
pub fn load_recogniser(
    path: Option<&Path>,
    band: Option<u32>,
    collected: super::Collected,
) -> Result<Arc<Recogniser>, String> {
    use crate::gesture::library::{read_library, shipped, MAX_LIBRARY_BYTES, SHIPPED_NAME};
    let band = band.map(|b| b as usize);
    // `gestures.collected` (issue 28 item 6): people's gestures weigh more than
    // generated ones, or replace them in the classes they were drawn for.
    let build = |mut lib: crate::gesture::library::Library, name: String| {
        let weight = match collected {
            super::Collected::Weigh(w) => w,
            super::Collected::Replace => {
                let dropped = lib.keep_collected_where_drawn();
                if dropped > 0 {
                    log::info!("{name}: {dropped} generated gestures left out (gestures.collected: Replace)");
                }
                1.0
            }
        };
        Recogniser::new(lib, name, band)
            .map(|r| Arc::new(r.with_collected_weight(weight)))
            .map_err(|e| e.to_string())
    };
    match path {
        // The shipped library has no gesture drawn by a person: `collected` changes
        // nothing, and its index is built once.
        None if band.is_none() => {
            static SHIPPED: OnceLock<Result<Arc<Recogniser>, String>> = OnceLock::new();
            SHIPPED
                .get_or_init(|| {
                    let lib = shipped().map_err(|e| e.to_string())?;
                    build(lib, format!("{SHIPPED_NAME} (shipped)"))
                })
                .clone()
        }
        None => {
            let lib = shipped().map_err(|e| e.to_string())?;
            build(lib, format!("{SHIPPED_NAME} (shipped)"))
        }
        Some(p) => {
            let bytes = read_bytes(p, MAX_LIBRARY_BYTES as u64).map_err(|e| e.to_string())?;
            let name = p.display().to_string();
            let lib = read_library(&bytes, &name).map_err(|e| e.to_string())?;
            build(lib, name)
        }
    }
}

/// Places `(field path, message)` problems in the config `text` they are about:
/// each at its field's line and column (or its nearest enclosing field's), in text
/// order.
pub fn locate_issues(text: &str, problems: Vec<(String, String)>) -> Vec<ConfigIssue> {
    let mut issues: Vec<ConfigIssue> = problems
        .into_iter()
        .map(|(field, message)| {
            let (line, column) = locate_field(text, &field).unwrap_or((0, 0));
            ConfigIssue {
                field,
                line,
                column,
                message,
            }
        })
        .collect();
    issues.sort_by_key(|i| (i.line, i.column));
    issues
}

/// Where `run` looks for its config when `--config` is not given, in order.
pub fn search_path() -> Vec<PathBuf> {
    let mut v = Vec::new();
    if let Some(p) = std::env::var_os("CROWDTOUCH_CONFIG") {
        v.push(PathBuf::from(p));
    }
    if let Some(d) = std::env::var_os("XDG_CONFIG_HOME") {
        v.push(PathBuf::from(d).join("crowdtouch/crowdtouch.ron"));
    } else if let Some(h) = std::env::var_os("HOME") {
        v.push(PathBuf::from(h).join(".config/crowdtouch/crowdtouch.ron"));
    }
    v.push(PathBuf::from("/etc/crowdtouch/crowdtouch.ron"));
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    fn issues(text: &str) -> Vec<ConfigIssue> {
        match Config::from_str(text, Path::new("t.ron")) {
            Err(Error::Invalid { issues, .. }) => issues,
            other => panic!("expected invalid, got {other:?}"),
        }
    }

    #[test]
    fn formation_bitmaps_load_next_to_the_config_and_their_problems_are_located() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("shapes")).unwrap();
        let mut pgm = b"P5 8 4 255\n".to_vec();
        pgm.extend((0..32).map(|i| if (i % 8) < 4 { 0u8 } else { 255 }));
        std::fs::write(dir.path().join("shapes/half.pgm"), &pgm).unwrap();
        let shapes = |text: &str| DEFAULT_CONFIG_RON.replace("        shapes: [],", text);
        let path = dir.path().join("c.ron");
        std::fs::write(
            &path,
            shapes("        shapes: [(name: \"half\", bitmap: Some((path: \"shapes/half.pgm\", c_min: (0, 0, 0), c_max: (9, 9, 9))))],"),
        )
        .unwrap();
        let c = Config::load(&path).unwrap();
        assert!(c.formation_library().get("half").is_some());
        std::fs::write(
            &path,
            shapes("        shapes: [\n            (name: \"gone\", bitmap: Some((path: \"shapes/none.png\", c_min: (0, 0, 0), c_max: (9, 9, 9)))),\n            (name: \"all\", bitmap: Some((path: \"shapes/half.pgm\", c_min: (0, 0, 0), c_max: (255, 255, 255)))),\n        ],"),
        )
        .unwrap();
        let e = Config::load(&path).unwrap_err().to_string();
        // The first listed shape is on the line after `shapes: [`.
        let line = DEFAULT_CONFIG_RON
            .lines()
            .position(|l| l == "        shapes: [],")
            .expect("the default config lists no shapes")
            + 2;
        assert!(
            e.contains(&format!(":{line}:"))
                && e.contains(
                    "field `formations.shapes[0].bitmap`: bitmap shapes/none.png: cannot read"
                )
                && e.contains("none.png: No such file"),
            "{e}"
        );
        assert!(
            e.contains(&format!(":{}:", line + 1)) && e.contains("field `formations.shapes[1].bitmap`: bitmap shapes/half.pgm: the colour range (0, 0, 0) ..= (255, 255, 255) selects all 32 pixels"),
            "{e}"
        );
    }

    #[test]
    fn formation_shapes_and_checkpoint_names_are_checked_where_they_are_written() {
        let shapes = |text: &str| DEFAULT_CONFIG_RON.replace("        shapes: [],", text);
        // A bow tie and a shape given twice, each at its own entry.
        let text = shapes(
            "        shapes: [\n            (name: \"bow\", outline: [(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]),\n            (name: \"t\", outline: [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]),\n            (name: \"t\", outline: [(0.0, 0.0), (2.0, 0.0), (0.0, 1.0)]),\n        ],",
        );
        let e = Config::from_str(&text, Path::new("f.ron"))
            .unwrap_err()
            .to_string();
        let line = |needle: &str| text.lines().position(|l| l.contains(needle)).unwrap() + 1;
        assert!(
            e.contains(&format!("f.ron:{}:", line("\"bow\"")))
                && e.contains(
                    "field `formations.shapes[0].outline`: outline: edges 0 and 2 cross or touch"
                ),
            "{e}"
        );
        assert!(
            e.contains(&format!("f.ron:{}:", line("(2.0, 0.0)")))
                && e.contains("field `formations.shapes[2].name`: formation `t` is defined twice"),
            "{e}"
        );
        let lambda = DEFAULT_CONFIG_RON.replace("lambda: 0.5", "lambda: 1.5");
        let e = Config::from_str(&lambda, Path::new("l.ron"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(
                "field `formations.lambda`: least-effort weight must be in 0 ..= 1, got 1.5"
            ),
            "{e}"
        );
        // A config without the section gets the shipped shapes; one that adds a
        // shape can use it in a scene.
        let bare: String = {
            let start = DEFAULT_CONFIG_RON.find("    formations: (").unwrap();
            let end = start + DEFAULT_CONFIG_RON[start..].find("\n    ),\n").unwrap() + 8;
            format!(
                "{}{}",
                &DEFAULT_CONFIG_RON[..start],
                &DEFAULT_CONFIG_RON[end..]
            )
        };
        let c = Config::from_str(&bare, Path::new("b.ron")).unwrap();
        assert!(c.formation_library().knows("arrow") && !c.formation_library().knows("t"));
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("gate.ron"),
            "(version: 1, bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),\n checkpoints: [(name: \"g\", formation: \"t\", region: Circle(centre_m: (3.0, 3.0), radius_m: 1.0))])",
        )
        .unwrap();
        let with_scene = |t: &str| t.replace("scene: None", "scene: Some(\"gate.ron\")");
        let cfg = dir.path().join("c.ron");
        std::fs::write(&cfg, with_scene(&bare)).unwrap();
        let e = Config::load(&cfg).unwrap_err().to_string();
        assert!(
            e.contains("field `scene`")
                && e.contains("gate.ron:2:")
                && e.contains("checkpoints[0].formation: no formation is called `t`"),
            "{e}"
        );
        std::fs::write(
            &cfg,
            with_scene(&shapes(
                "        shapes: [(name: \"t\", outline: [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])],",
            )),
        )
        .unwrap();
        let c = Config::load(&cfg).unwrap();
        assert_eq!(c.loaded_scene().unwrap().checkpoints()[0].formation, "t");
    }

    #[test]
    fn scene_field_loads_shipped_embedded_and_reports_bad_scenes() {
        let with = |scene: &str| DEFAULT_CONFIG_RON.replace("scene: None", scene);
        // No scene: nothing loaded.
        let c = Config::embedded_default();
        assert!(c.scene.is_none() && c.loaded_scene().is_none());
        // A shipped name that does not exist on disk resolves to the embedded copy.
        let c = Config::from_str(
            &with("scene: Some(\"/nonexistent/scenes/single_block.ron\")"),
            Path::new("t.ron"),
        )
        .unwrap();
        assert_eq!(c.loaded_scene().unwrap().name(), "single block");
        // Relative to the config file.
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("bad.ron"),
            "(version: 1, bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),\n obstacles: [(parts: [Circle(centre_m: (4.0, 4.0), radius_m: -1.0)])])",
        )
        .unwrap();
        let cfg = dir.path().join("c.ron");
        std::fs::write(&cfg, with("scene: Some(\"bad.ron\")")).unwrap();
        let e = Config::load(&cfg).unwrap_err().to_string();
        let line = with("scene: Some(\"bad.ron\")")
            .lines()
            .position(|l| l.contains("scene: Some"))
            .unwrap()
            + 1;
        assert!(e.contains(&format!("c.ron:{line}:")), "{e}");
        assert!(e.contains("field `scene`"), "{e}");
        assert!(e.contains("bad.ron:2:"), "{e}");
        // A missing file that is not a shipped name.
        let e = Config::from_str(&with("scene: Some(\"nope.ron\")"), Path::new("t.ron"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("field `scene`") && e.contains("nope.ron"), "{e}");
    }

    #[test]
    fn embedded_default_is_valid() {
        let c = Config::embedded_default();
        assert_eq!(c.crowd.agents, 100);
        assert_eq!(c.controls.group_window_ms, 150);
    }

    #[test]
    fn unknown_field_is_an_error_with_its_place() {
        let text =
            DEFAULT_CONFIG_RON.replacen("agents: 100,", "agents: 100,\n        agnets: 5,", 1);
        let is = issues(&text);
        assert_eq!(is.len(), 1);
        assert_eq!(is[0].field, "crowd.agnets");
        let expect_line = text.lines().position(|l| l.contains("agnets")).unwrap() + 1;
        assert_eq!(is[0].line, expect_line);
        assert!(is[0].message.contains("agnets"), "{}", is[0].message);
    }

    #[test]
    fn syntax_error_has_position() {
        let is = issues("(version: 1,, )");
        assert_eq!(is[0].line, 1);
        assert!(is[0].column > 0);
    }

    #[test]
    fn missing_field_is_named() {
        let text = DEFAULT_CONFIG_RON.replacen("max_speed_m_s: 1.5,", "", 1);
        let is = issues(&text);
        assert!(is[0].field.ends_with("max_speed_m_s"), "{is:?}");
        assert!(is[0].message.contains("max_speed_m_s"));
    }

    #[test]
    fn missing_file_names_the_path() {
        let e = Config::load(Path::new("/nonexistent/crowdtouch.ron")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/crowdtouch.ron"), "{e}");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 256, ..Default::default() })]
        /// Arbitrary text never panics the parser, and every error points inside it.
        #[test]
        fn arbitrary_text_never_panics(text in "\\PC{0,200}") {
            if let Err(Error::Invalid { issues, .. }) = Config::from_str(&text, Path::new("p.ron")) {
                let lines = text.lines().count().max(1);
                for i in issues {
                    proptest::prop_assert!(i.line <= lines + 1, "line {} of {}", i.line, lines);
                }
            }
        }

        /// The default config with a slice cut out or repeated: an error with a place,
        /// or (rarely) still a valid config; never a panic.
        #[test]
        fn mutated_default_never_panics(a in 0usize..4000, len in 0usize..80, dup in proptest::bool::ANY) {
            let t = DEFAULT_CONFIG_RON;
            let a = a.min(t.len());
            let b = (a + len).min(t.len());
            if !t.is_char_boundary(a) || !t.is_char_boundary(b) {
                return Ok(());
            }
            let mutated = if dup { format!("{}{}", &t[..b], &t[a..]) } else { format!("{}{}", &t[..a], &t[b..]) };
            match Config::from_str(&mutated, Path::new("m.ron")) {
                Ok(_) => {}
                Err(Error::Invalid { issues, .. }) => proptest::prop_assert!(!issues.is_empty()),
                Err(e) => proptest::prop_assert!(false, "unexpected error kind {e}"),
            }
        }
    }

    #[test]
    fn garbage_never_panics() {
        for t in [
            "",
            "(",
            ")",
            "((((",
            "\"",
            "/*",
            "(version: \"x\")",
            "[1,2",
            "\u{0}",
        ] {
            assert!(Config::from_str(t, Path::new("g")).is_err());
        }
    }
}
