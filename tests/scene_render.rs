//! `crowdtouch scene render`: the picture has every layer, is well-formed XML, is
//! byte-identical across runs, matches the shipped `docs/scenes/*.svg`, and bad
//! input gets a clear message and a non-zero exit code.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
}

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn render(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    bin()
        .args(["scene", "render"])
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

/// One element of the document: its name and attributes, in document order.
#[derive(Debug)]
struct Element {
    name: String,
    attrs: BTreeMap<String, String>,
    /// Text directly inside it (entities left as written).
    text: String,
}

/// A minimal well-formedness check: tags balance, attribute values are quoted and
/// unique per element, `&` only starts a known entity, no `<` in text or values.
/// Returns every element.
fn parse_xml(doc: &str) -> Vec<Element> {
    let b = doc.as_bytes();
    let mut i = 0;
    let mut stack: Vec<(String, usize)> = Vec::new();
    let mut out: Vec<Element> = Vec::new();
    let check_entities = |t: &str| {
        let mut rest = t;
        while let Some(k) = rest.find('&') {
            let tail = &rest[k..];
            let end = tail.find(';').unwrap_or_else(|| panic!("bare & in {t:?}"));
            let ent = &tail[1..end];
            assert!(
                matches!(ent, "amp" | "lt" | "gt" | "quot" | "apos") || ent.starts_with('#'),
                "unknown entity &{ent}; in {t:?}"
            );
            rest = &tail[end + 1..];
        }
    };
    let mut roots = 0;
    while i < b.len() {
        if b[i] != b'<' {
            let end = doc[i..].find('<').map_or(b.len(), |k| i + k);
            let text = &doc[i..end];
            check_entities(text);
            if stack.is_empty() {
                assert!(text.trim().is_empty(), "text outside the root: {text:?}");
            } else {
                let owner = stack.last().unwrap().1;
                out[owner].text.push_str(text);
            }
            i = end;
            continue;
        }
        let end = doc[i..].find('>').expect("unclosed tag") + i;
        let tag = &doc[i + 1..end];
        i = end + 1;
        if tag.starts_with('?') || tag.starts_with("!--") {
            continue;
        }
        if let Some(name) = tag.strip_prefix('/') {
            let (open, _) = stack.pop().expect("close without open");
            assert_eq!(open, name.trim(), "mismatched close tag");
            continue;
        }
        let self_closing = tag.ends_with('/');
        let body = tag.trim_end_matches('/');
        let name_end = body.find(char::is_whitespace).unwrap_or(body.len());
        let name = &body[..name_end];
        assert!(
            !name.is_empty()
                && name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == ':'),
            "bad element name {name:?}"
        );
        let mut attrs = BTreeMap::new();
        let mut rest = body[name_end..].trim_start();
        while !rest.is_empty() {
            let eq = rest
                .find('=')
                .unwrap_or_else(|| panic!("attribute without value in <{tag}>"));
            let key = rest[..eq].trim();
            assert!(
                !key.is_empty()
                    && key
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || "-:_".contains(c)),
                "bad attribute name {key:?}"
            );
            let after = &rest[eq + 1..];
            let q = after.chars().next().expect("attribute value");
            assert!(q == '"' || q == '\'', "unquoted attribute {key} in <{tag}>");
            let close = after[1..].find(q).expect("unterminated attribute value") + 1;
            let value = &after[1..close];
            assert!(!value.contains('<'), "< in attribute {key}");
            check_entities(value);
            assert!(
                attrs.insert(key.to_string(), value.to_string()).is_none(),
                "duplicate attribute {key} in <{tag}>"
            );
            rest = after[close + 1..].trim_start();
        }
        if stack.is_empty() {
            roots += 1;
        }
        out.push(Element {
            name: name.to_string(),
            attrs,
            text: String::new(),
        });
        if !self_closing {
            stack.push((name.to_string(), out.len() - 1));
        }
    }
    assert!(stack.is_empty(), "unclosed elements: {stack:?}");
    assert_eq!(roots, 1, "one root element");
    out
}

fn count(els: &[Element], name: &str, class: &str) -> usize {
    els.iter()
        .filter(|e| e.name == name && e.attrs.get("class").map(String::as_str) == Some(class))
        .count()
}

#[test]
fn xml_checker_rejects_broken_documents() {
    for bad in [
        "<svg><g></svg>",
        "<svg a=1/>",
        "<svg a=\"1\" a=\"2\"/>",
        "<svg>&nbsp;</svg>",
        "<svg/><svg/>",
        "<svg><text>a & b</text></svg>",
    ] {
        assert!(
            std::panic::catch_unwind(|| parse_xml(bad)).is_err(),
            "accepted {bad}"
        );
    }
    assert_eq!(
        parse_xml("<svg x=\"1\"><g/><text>a &amp; b</text></svg>").len(),
        3
    );
}

#[test]
fn renders_a_shipped_scene_with_every_layer() {
    let dir = tempfile::tempdir().unwrap();
    let out_path = dir.path().join("corridor.svg");
    let out = render(
        &repo("config/scenes/corridor.ron"),
        &out_path,
        &["--agents", "12"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(
        summary.contains("goal (15.00, 4.50)")
            && summary.contains("12 of 12 routes reach the goal"),
        "{summary}"
    );
    let doc = std::fs::read_to_string(&out_path).unwrap();
    let els = parse_xml(&doc);
    let root = &els[0];
    assert_eq!(root.name, "svg");
    assert_eq!(
        root.attrs.get("xmlns").map(String::as_str),
        Some("http://www.w3.org/2000/svg")
    );
    // Two walls of one part each, two checkpoints with their formations.
    assert_eq!(count(&els, "polygon", "obstacle"), 2);
    assert_eq!(count(&els, "polygon", "checkpoint"), 2);
    let formations: Vec<&str> = els
        .iter()
        .filter(|e| e.attrs.get("class").map(String::as_str) == Some("formation"))
        .map(|e| e.text.as_str())
        .collect();
    assert_eq!(formations, ["arrow", "square"]);
    // The heat map: several colour levels plus the blocked walls.
    assert_eq!(count(&els, "g", "heatmap"), 1);
    let heat = count(&els, "path", "heat");
    assert!(heat >= 20, "{heat} heat paths");
    assert!(
        doc.contains(r##"class="heat" fill="#9c9c9c""##),
        "no blocked cells"
    );
    assert!(count(&els, "path", "contour") >= 3);
    // One route and one dot per agent; each route ends at the goal.
    assert_eq!(count(&els, "circle", "agent"), 12);
    assert_eq!(count(&els, "polyline", "route"), 12);
    for e in els
        .iter()
        .filter(|e| e.attrs.get("class").map(String::as_str) == Some("route"))
    {
        let pts = &e.attrs["points"];
        assert!(pts.split(' ').count() >= 2);
        assert!(
            !e.attrs.contains_key("stroke-dasharray"),
            "route stopped early: {pts}"
        );
    }
    // Title, legend with every motion type and its Table 1 factor, scale bar.
    let title = els
        .iter()
        .find(|e| e.attrs.get("class").map(String::as_str) == Some("title"))
        .unwrap();
    assert!(
        title.text.contains("corridor")
            && title.text.contains("320 × 180")
            && title.text.contains("goal (15.00, 4.50)"),
        "{}",
        title.text
    );
    for label in [
        "run ×1.00",
        "crawl ×0.33",
        "duck ×0.30",
        "swim ×0.46",
        "jump ×1.24",
        "climb up ×0.50",
        "climb down ×0.48",
    ] {
        assert!(
            doc.contains(&format!(">{label}</text>")),
            "legend misses {label}"
        );
    }
    assert!(doc.contains("travel time to goal (s)"));
    assert_eq!(count(&els, "g", "scale-bar"), 1);
    assert!(doc.contains(">5 m</text>"));
}

#[test]
fn render_is_deterministic_and_draws_moving_obstacles_at_t() {
    let dir = tempfile::tempdir().unwrap();
    let street = repo("config/scenes/street.ron");
    let (a, b) = (dir.path().join("a.svg"), dir.path().join("b.svg"));
    let args = [
        "--t", "2.5", "--goal", "14,4", "--cell-m", "0.1", "--agents", "7",
    ];
    for p in [&a, &b] {
        let out = render(&street, p, &args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let (da, db) = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert_eq!(da, db, "two runs differ");
    let doc = String::from_utf8(da).unwrap();
    let els = parse_xml(&doc);
    assert_eq!(count(&els, "polygon", "moving-obstacle"), 4);
    assert_eq!(count(&els, "polyline", "path"), 4);
    assert_eq!(count(&els, "circle", "obstacle"), 2);
    assert_eq!(count(&els, "polygon", "patch"), 1);
    assert_eq!(count(&els, "polyline", "route"), 7);
    assert!(doc.contains("t = 2.5 s"));
    // Another time moves the cars.
    let c = dir.path().join("c.svg");
    assert!(render(
        &street,
        &c,
        &["--t", "0", "--goal", "14,4", "--cell-m", "0.1", "--agents", "7"]
    )
    .status
    .success());
    assert_ne!(std::fs::read(&c).unwrap(), doc.as_bytes());
}

#[test]
fn bad_input_gets_a_clear_message_and_a_non_zero_exit() {
    let dir = tempfile::tempdir().unwrap();
    let corridor = repo("config/scenes/corridor.ron");
    let out_path = dir.path().join("x.svg");
    let fail = |scene: &Path, out: &Path, extra: &[&str], code: i32, needle: &str| {
        let o = render(scene, out, extra);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{extra:?}: {err}");
        assert!(
            err.contains(needle),
            "{extra:?}: expected {needle:?} in {err}"
        );
        assert!(!out.exists(), "{extra:?}: wrote {}", out.display());
    };
    fail(
        &corridor,
        &out_path,
        &["--goal", "17,4"],
        2,
        "outside the scene bounds (0, 0)..(16, 9)",
    );
    fail(
        &corridor,
        &out_path,
        &["--goal", "-1,4"],
        2,
        "outside the scene bounds",
    );
    fail(
        &corridor,
        &out_path,
        &["--goal", "13,1"],
        2,
        "inside obstacle \"north wall\"",
    );
    fail(&corridor, &out_path, &["--goal", "13"], 2, "expected X,Y");
    fail(&corridor, &out_path, &["--cell-m", "0"], 2, "--cell-m");
    fail(&corridor, &out_path, &["--cell-m", "0.001"], 2, "--cell-m");
    fail(&corridor, &out_path, &["--t", "nan"], 2, "--t");
    let street = repo("config/scenes/street.ron");
    // At t = 0 the bus (4 m long) is centred at x = 2.2 + 1.5 m/s × 3 s = 6.7 on y = 8.4.
    fail(
        &street,
        &out_path,
        &["--goal", "6,8.4"],
        2,
        "inside moving obstacle \"bus\"",
    );

    let bad = dir.path().join("bad.ron");
    std::fs::write(
        &bad,
        "(\n    version: 1,\n    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),\n    obstacles: [(name: \"dot\", parts: [Circle(centre_m: (4.0, 4.0), radius_m: -1.0)])],\n)\n",
    )
    .unwrap();
    fail(&bad, &out_path, &[], 1, "bad.ron:4:");
    fail(&dir.path().join("nope.ron"), &out_path, &[], 1, "nope.ron");
    let unwritable = dir.path().join("no-such-dir").join("x.svg");
    fail(&corridor, &unwritable, &[], 1, "writing");
}

#[test]
fn scene_help_lists_render() {
    let out = bin().args(["scene", "--help"]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("render") && text.contains("check"), "{text}");
    let out = bin().args(["scene", "render", "--help"]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    for opt in ["--out", "--goal", "--agents", "--t", "--cell-m"] {
        assert!(text.contains(opt), "render --help misses {opt}:\n{text}");
    }
}

/// `docs/scenes/<name>.svg` is what `scene render config/scenes/<name>.ron` draws
/// today (regenerate with the loop in `docs/scenes/README.md`).
#[test]
fn docs_scene_pictures_are_current_and_small() {
    let dir = tempfile::tempdir().unwrap();
    let mut names = Vec::new();
    for e in std::fs::read_dir(repo("config/scenes")).unwrap() {
        let scene = e.unwrap().path();
        let stem = scene.file_stem().unwrap().to_string_lossy().into_owned();
        let fresh = dir.path().join(format!("{stem}.svg"));
        let out = render(&scene, &fresh, &[]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let fresh = std::fs::read(&fresh).unwrap();
        assert!(fresh.len() < 300_000, "{stem}: {} bytes", fresh.len());
        parse_xml(std::str::from_utf8(&fresh).unwrap());
        let shipped = repo(&format!("docs/scenes/{stem}.svg"));
        let shipped =
            std::fs::read(&shipped).unwrap_or_else(|e| panic!("{}: {e}", shipped.display()));
        assert!(
            shipped == fresh,
            "docs/scenes/{stem}.svg is out of date: regenerate it (docs/scenes/README.md)"
        );
        names.push(stem);
    }
    assert_eq!(names.len(), 7, "{names:?}");
}

#[test]
fn unreachable_cells_have_their_own_fill_and_agents_there_get_no_route() {
    let dir = tempfile::tempdir().unwrap();
    // A walled yard (one obstacle of four overlapping walls) around part of the
    // crowd start: the agents inside cannot reach the goal outside.
    let scene = dir.path().join("yard.ron");
    std::fs::write(
        &scene,
        "(\n    version: 1,\n    name: \"yard\",\n    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),\n    obstacles: [(name: \"yard wall\", parts: [\n        Polygon(vertices_m: [(5.0, 2.0), (8.0, 2.0), (8.0, 2.3), (5.0, 2.3)]),\n        Polygon(vertices_m: [(5.0, 6.7), (8.0, 6.7), (8.0, 7.0), (5.0, 7.0)]),\n        Polygon(vertices_m: [(5.0, 2.0), (5.3, 2.0), (5.3, 7.0), (5.0, 7.0)]),\n        Polygon(vertices_m: [(7.7, 2.0), (8.0, 2.0), (8.0, 7.0), (7.7, 7.0)]),\n    ])],\n)\n",
    )
    .unwrap();
    let out_path = dir.path().join("yard.svg");
    let out = render(&scene, &out_path, &["--agents", "20", "--cell-m", "0.1"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc = std::fs::read_to_string(&out_path).unwrap();
    let els = parse_xml(&doc);
    assert!(doc.contains(r#"class="heat" fill="url(#unreachable)""#));
    let agents = count(&els, "circle", "agent");
    let routes = count(&els, "polyline", "route");
    assert_eq!(agents, 20);
    assert!(
        routes > 0 && routes < agents,
        "{routes} routes for {agents} agents"
    );
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(
        summary.contains(&format!("{routes} of {routes} routes reach")),
        "{summary}"
    );
}
