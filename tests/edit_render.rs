//! `crowdtouch edit render`: a small crossing crowd dragged with a fixed place and
//! kept apart by retiming is drawn as well-formed SVG with every layer; an existing
//! picture is kept without `--force`; a bad script line is named `file:line`.

use std::fmt::Write;
use std::path::Path;
use std::process::{Command, Output};

/// Two groups of three walking across each other (CSV `t,id,x,y`, 0.2 s step).
fn crossing_tracks(dir: &Path) -> String {
    let mut s = String::new();
    for k in 0..=40 {
        let t = 0.2 * k as f64;
        for i in 0..3 {
            let dy = 0.8 * i as f64;
            let _ = writeln!(s, "{t:.1},{i},{:.3},{:.3}", 0.25 * t, 2.0 + dy);
            let _ = writeln!(s, "{t:.1},{},{:.3},{:.3}", 10 + i, 1.0 + dy, 0.25 * t);
        }
    }
    let p = dir.join("crossing.csv");
    std::fs::write(&p, s).unwrap();
    p.display().to_string()
}

fn script(dir: &Path, text: &str) -> String {
    let p = dir.join("edit.ron");
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

fn render(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
        .args(["edit", "render"])
        .args(args)
        .output()
        .unwrap()
}

/// Tags open and close in order (comments, declarations and self-closing tags
/// aside); returns the element names seen.
fn balanced(svg: &str) -> Vec<String> {
    let mut stack: Vec<String> = Vec::new();
    let mut seen = Vec::new();
    let mut rest = svg;
    while let Some(i) = rest.find('<') {
        let end = rest[i..].find('>').expect("unterminated tag") + i;
        let tag = &rest[i + 1..end];
        rest = &rest[end + 1..];
        assert!(!tag.contains('<'), "`<` inside a tag: {tag}");
        if tag.starts_with('?') || tag.starts_with('!') {
            continue;
        }
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(stack.pop().as_deref(), Some(name.trim()), "closing {name}");
            continue;
        }
        let name: String = tag
            .chars()
            .take_while(|c| !c.is_whitespace() && *c != '/')
            .collect();
        assert_eq!(
            tag.matches('"').count() % 2,
            0,
            "unbalanced quotes in <{tag}>"
        );
        seen.push(name.clone());
        if !tag.ends_with('/') {
            stack.push(name);
        }
    }
    assert!(stack.is_empty(), "unclosed: {stack:?}");
    assert!(rest.trim().is_empty());
    seen
}

#[test]
fn renders_every_layer_as_well_formed_svg() {
    let dir = tempfile::tempdir().unwrap();
    let tracks = crossing_tracks(dir.path());
    let ops = script(
        dir.path(),
        "(ops: [\n Select(ids: Some([0, 1, 2])),\n Fix(at: [(0.0, 2.0)]),\n Drag(from: (8.0, 3.6), to: (8.5, 4.5)),\n])\n",
    );
    let out_path = dir.path().join("out.svg");
    let out = render(&[
        &tracks,
        "--ops",
        &ops,
        "--avoid-collisions",
        "--threshold",
        "0.5",
        "--at",
        "4",
        "-o",
        out_path.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = std::fs::read_to_string(&out_path).unwrap();
    assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
    let names = balanced(&svg);
    // Every layer is there, each shape named by its class (`crowdtouch::picture`).
    for class in [
        "world",
        "grid",
        "before",
        "after",
        "cage-mesh",
        "cage-rest",
        "cage-deformed",
        "handle",
        "drag",
        "fixed",
        "before-at",
        "after-at",
        "collision-before",
        "axes",
        "legend",
        "summary",
    ] {
        assert!(svg.contains(&format!("class=\"{class}\"")), "no {class}");
    }
    assert!(names.iter().filter(|n| *n == "polyline").count() >= 6);
    // The groups cross: collisions before, drawn as rings.
    assert!(
        svg.lines()
            .any(|l| l.starts_with("<circle") && l.contains("class=\"collision-before\"")),
        "no collision ring"
    );
    assert!(svg.contains("time after the edit (s)"));
    assert!(svg.contains("pairs closer than 0.5 m:"));
    // Coordinates in page pixels, at most one decimal.
    let line = svg
        .lines()
        .find(|l| l.contains("class=\"after\"") && l.contains("points=\""))
        .expect("a track after");
    let pts = &line[line.find("points=\"").unwrap() + 8..];
    let pts = &pts[..pts.find('"').unwrap()];
    for v in pts.split([' ', ',']) {
        let decimals = v.split('.').nth(1).map_or(0, str::len);
        assert!(decimals <= 1, "{v}");
    }
}

#[test]
fn keeps_an_existing_picture_without_force() {
    let dir = tempfile::tempdir().unwrap();
    let tracks = crossing_tracks(dir.path());
    let out_path = dir.path().join("out.svg");
    std::fs::write(&out_path, "mine").unwrap();
    let out = render(&[&tracks, "-o", out_path.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--force"));
    assert_eq!(std::fs::read_to_string(&out_path).unwrap(), "mine");
    let out = render(&[&tracks, "-o", out_path.to_str().unwrap(), "--force"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    balanced(&std::fs::read_to_string(&out_path).unwrap());
}

#[test]
fn a_bad_script_line_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let tracks = crossing_tracks(dir.path());
    let ops = script(
        dir.path(),
        "(ops: [\n Select(ids: Some([0, 1, 2])),\n Select(ids: Some([99])),\n Drag(from: (1.0, 2.0), to: (1.0, 3.0)),\n])\n",
    );
    let out_path = dir.path().join("out.svg");
    let out = render(&[&tracks, "--ops", &ops, "-o", out_path.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("{ops}:3:")), "{err}");
    assert!(!out_path.exists());
    let bad = script(
        dir.path(),
        "(ops: [\n Select(ids: Some([0])),\n Drag(from: (1.0, 2.0)),\n])\n",
    );
    let out = render(&[&tracks, "--ops", &bad, "-o", out_path.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("{bad}:3:")), "{err}");
}
