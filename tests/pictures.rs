//! The pictures the commands draw still show what they showed: the same circles,
//! lines, rectangles and texts at the same page coordinates (within 0.15 px), however
//! they are styled, ordered and grouped.
//!
//! `tests/fixtures/pictures/` holds one reference picture per renderer (`replay
//! --svg`, `scene render`, `formations`, `transform --svg`, `transform compare
//! --svg` with and without `--lambdas`, `edit render`), drawn by the binary of
//! commit d72b05db with the commands of its `commands.txt`.
//! [`every_picture_still_shows_what_its_reference_shows`] draws each again with this
//! build and compares what is drawn, not the bytes: `svg_shapes` reads the shapes
//! of a picture in page coordinates, `same_data` matches them as multisets.
//!
//! [`pictures_in_two_folders_show_the_same_data`] (ignored; it needs two folders)
//! compares every `*.svg` under `$CROWDTOUCH_PICTURES_BEFORE` with the file of the
//! same relative path under `$CROWDTOUCH_PICTURES_AFTER`, e.g. the committed
//! `docs/` against the figures `scripts/docs-figures.sh --out DIR` drew again.

#[path = "pictures/same_data.rs"]
mod same_data;
#[path = "pictures/svg_shapes.rs"]
mod svg_shapes;

use same_data::{same_data, TOLERANCE_PX};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use svg_shapes::{shapes, Kind, Shape};

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn fixtures() -> PathBuf {
    repo().join("tests/fixtures/pictures")
}

/// One line of `commands.txt`: the reference's file name and the arguments.
struct Reference {
    file: String,
    args: Vec<String>,
}

fn references() -> Vec<Reference> {
    let path = fixtures().join("commands.txt");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| {
            let mut words = l.split_whitespace().map(String::from);
            let file = words.next().expect("a file name");
            Reference {
                file,
                args: words.collect(),
            }
        })
        .collect()
}

fn read_shapes(path: &Path) -> Vec<Shape> {
    let svg = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    shapes(&svg).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// "12 circle, 3 rect, ..." for the log.
fn census(s: &[Shape]) -> String {
    Kind::ALL
        .iter()
        .map(|&k| {
            format!(
                "{} {}",
                s.iter().filter(|x| x.kind == k).count(),
                k.as_str()
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn ms(d: Duration) -> String {
    format!("{:.1} ms", d.as_secs_f64() * 1e3)
}

#[test]
fn every_picture_still_shows_what_its_reference_shows() {
    let refs = references();
    assert!(
        refs.len() >= 7,
        "commands.txt lists {} pictures",
        refs.len()
    );
    let scratch = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for r in &refs {
        let out = scratch.path().join(&r.file);
        let args: Vec<String> = r
            .args
            .iter()
            .map(|a| {
                a.replace("{out}", &out.to_string_lossy())
                    .replace("{dir}", &scratch.path().to_string_lossy())
            })
            .collect();
        let t0 = Instant::now();
        // The repository's root, as make.sh runs them; no user or system config.
        let run = Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
            .args(&args)
            .current_dir(repo())
            .env_remove("CROWDTOUCH_CONFIG")
            .env_remove("RUST_LOG")
            .env("XDG_CONFIG_HOME", scratch.path())
            .env("HOME", scratch.path())
            .stdin(Stdio::null())
            .output()
            .unwrap();
        let drawn = t0.elapsed();
        assert!(
            run.status.success(),
            "crowdtouch {}: {}\n{}",
            args.join(" "),
            run.status,
            String::from_utf8_lossy(&run.stderr)
        );
        let t1 = Instant::now();
        let (reference, now) = (read_shapes(&fixtures().join(&r.file)), read_shapes(&out));
        let read = t1.elapsed();
        let t2 = Instant::now();
        let verdict = same_data(&r.file, &reference, &now, TOLERANCE_PX);
        eprintln!(
            "{}: {} ({}); drawn in {}, read in {}, compared in {}",
            r.file,
            if verdict.is_ok() {
                "same data"
            } else {
                "DIFFERS"
            },
            census(&reference),
            ms(drawn),
            ms(read),
            ms(t2.elapsed())
        );
        if let Err(m) = verdict {
            failures.push(format!("crowdtouch {}\n{m}", r.args.join(" ")));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} pictures no longer show what their references show \
         (tests/fixtures/pictures/README.md says how they were made):\n\n{}",
        failures.len(),
        refs.len(),
        failures.join("\n")
    );
}

/// Every `*.svg` under `dir`, as paths relative to it, sorted.
fn svgs_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display()));
        for e in entries {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "svg") {
                out.push(p.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// `CROWDTOUCH_PICTURES_BEFORE=docs CROWDTOUCH_PICTURES_AFTER=/tmp/docs-after cargo
/// test --release --test pictures -- --ignored`: every picture under BEFORE
/// against the one of the same relative path under AFTER; all differences are
/// reported, then the test fails if there was any.
#[test]
#[ignore = "needs CROWDTOUCH_PICTURES_BEFORE and CROWDTOUCH_PICTURES_AFTER"]
fn pictures_in_two_folders_show_the_same_data() {
    let var = |name: &str| {
        PathBuf::from(std::env::var_os(name).unwrap_or_else(|| {
            panic!(
                "set {name}: CROWDTOUCH_PICTURES_BEFORE and CROWDTOUCH_PICTURES_AFTER are two \
                 folders whose *.svg files (same relative paths) are compared"
            )
        }))
    };
    let (before, after) = (
        var("CROWDTOUCH_PICTURES_BEFORE"),
        var("CROWDTOUCH_PICTURES_AFTER"),
    );
    let files = svgs_under(&before);
    assert!(!files.is_empty(), "no *.svg under {}", before.display());
    let (mut same, mut problems) = (0, Vec::new());
    for rel in &files {
        let (b, a) = (before.join(rel), after.join(rel));
        if !a.exists() {
            eprintln!("{}: MISSING in {}", rel.display(), after.display());
            problems.push(format!(
                "{}: missing in {}\n",
                rel.display(),
                after.display()
            ));
            continue;
        }
        let t = Instant::now();
        let name = rel.display().to_string();
        match same_data(&name, &read_shapes(&b), &read_shapes(&a), TOLERANCE_PX) {
            Ok(()) => {
                same += 1;
                eprintln!("{name}: same data ({})", ms(t.elapsed()));
            }
            Err(m) => {
                eprintln!("{name}: DIFFERS ({})", ms(t.elapsed()));
                problems.push(m);
            }
        }
    }
    eprintln!(
        "{} pictures: {same} show the same data, {} differ or are missing",
        files.len(),
        problems.len()
    );
    assert!(
        problems.is_empty(),
        "{} of {} pictures under {} are not shown the same under {}:\n\n{}",
        problems.len(),
        files.len(),
        before.display(),
        after.display(),
        problems.join("\n")
    );
}

// ---- the extractor and the comparator on small pictures

fn svg(body: &str) -> Vec<Shape> {
    let doc = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="100" viewBox="0 0 200 100">{body}</svg>"#
    );
    shapes(&doc).unwrap_or_else(|e| panic!("{e}\n{doc}"))
}

fn check(a: &str, b: &str) -> Result<(), String> {
    same_data("test.svg", &svg(a), &svg(b), TOLERANCE_PX)
}

fn close(p: (f64, f64), q: (f64, f64)) -> bool {
    (p.0 - q.0).abs() < 1e-9 && (p.1 - q.1).abs() < 1e-9
}

#[test]
fn a_relative_path_equals_its_absolute_twin() {
    let relative = r#"<path d="m10 10 l5 0 h5 v5 c1 1 2 2 3 3 s4 4 5 5 q1 0 2 2 t3 3 a4 4 0 0 1 8 0 z m40 40 l1 1"/>"#;
    let absolute = r#"<path d="M10 10 L15 10 H20 V15 C21 16 22 17 23 18 S27 22 28 23 Q29 23 30 25 T33 28 A4 4 0 0 1 41 28 Z M50 50 L51 51"/>"#;
    let (r, a) = (svg(relative), svg(absolute));
    assert_eq!(r.len(), 2, "{r:?}");
    assert_eq!(r.len(), a.len());
    for (p, q) in r.iter().zip(&a) {
        assert_eq!(p.points.len(), q.points.len(), "{p:?} / {q:?}");
        assert!(
            p.points.iter().zip(&q.points).all(|(&x, &y)| close(x, y)),
            "{p:?} / {q:?}"
        );
    }
    // S and T write out their reflected control points: (23,18) mirrors (22,17)
    // into (24,19); the T after Q(29,23)->(30,25) has control point (31,27).
    assert!(close(r[0].points[7], (24.0, 19.0)), "{:?}", r[0].points);
    assert!(close(r[0].points[12], (31.0, 27.0)), "{:?}", r[0].points);
    // The arc from (33,28) to (41,28) of radius 4 has its centre half-way.
    assert!(close(r[0].points[14], (37.0, 28.0)), "{:?}", r[0].points);
    assert!(check(relative, absolute).is_ok());
}

#[test]
fn a_group_transform_matrix_is_applied() {
    // World metres, y up, 88 px/m, the origin at (12, 312.8): as edit render draws.
    let s = svg(
        r#"<g transform="matrix(88,0,0,-88,12,312.8)"><g transform="translate(1 2)">
             <circle cx="0.5" cy="0.25" r="0.1"/><polyline points="0,0 1,1"/></g></g>"#,
    );
    assert_eq!(s[0].kind, Kind::Circle);
    assert!(
        close(s[0].points[0], (12.0 + 1.5 * 88.0, 312.8 - 2.25 * 88.0)),
        "{s:?}"
    );
    assert!((s[0].points[1].0 - 8.8).abs() < 1e-9 && (s[0].points[1].1 - 8.8).abs() < 1e-9);
    assert!(
        close(s[1].points[1], (12.0 + 2.0 * 88.0, 312.8 - 3.0 * 88.0)),
        "{s:?}"
    );
    // rotate about a centre, scale, and a viewBox mapped onto a larger page.
    let r = svg(
        r#"<text x="14" y="50" transform="rotate(-90 14 50)">y</text><g transform="rotate(90) scale(2)"><line x1="1" y1="0" x2="0" y2="0"/></g>"#,
    );
    assert!(close(r[0].points[0], (14.0, 50.0)), "{r:?}");
    assert!(close(r[1].points[0], (0.0, 2.0)), "{r:?}");
    let doc = r#"<svg xmlns="http://www.w3.org/2000/svg" width="400" height="200" viewBox="0 0 200 100"><circle cx="10" cy="20" r="3"/></svg>"#;
    let c = &shapes(doc).unwrap()[0];
    assert!(
        close(c.points[0], (20.0, 40.0)) && close(c.points[1], (6.0, 6.0)),
        "{c:?}"
    );
}

#[test]
fn the_same_picture_reordered_regrouped_and_restyled_compares_equal() {
    let before = r##"
        <rect width="100%" height="100%" fill="#fff"/>
        <circle cx="10.0" cy="20.0" r="2.2" fill="#c0392b"/>
        <circle cx="30.0" cy="40.0" r="2.2" fill="#c0392b"/>
        <polyline points="1.0,2.0 3.0,4.0 5.0,6.0" stroke="#555"/>
        <polygon points="50,50 60,50 55,58" fill="none"/>
        <path class="heat" d="M100 10h20v6h-20zM100 16h20v6h-20z"/>
        <line x1="0" y1="90" x2="200" y2="90" stroke="#eee"/>
        <text x="57.0" y="294.0" text-anchor="end">0.50</text>
        <g><title>north wall</title><rect x="5" y="5" width="10" height="2"/></g>"##;
    // Reordered; grouped and drawn in metres at 100 px/m (millimetres); the polyline
    // written backwards, the triangle as a path starting elsewhere, the heat strips
    // as <rect>s, the line as a path, numbers formatted otherwise, every style changed.
    let after = r##"
        <g transform="scale(100)" stroke-width="0.01" class="world">
          <circle cx="0.300" cy="0.400" r="0.022" fill="red"/>
          <circle cx="0.1" cy="0.2" r="0.022"/>
        </g>
        <g id="strips" fill="blue"><rect x="100" y="16" width="20" height="6"/><rect x="100" y="10" width="20" height="6"/></g>
        <path d="M55,58 L50,50 L60,50 Z" stroke="green"/>
        <path d="M5,6 L3,4 L1,2" opacity="0.5"/>
        <text x="57" y="294" font-size="20" fill="black">0.5</text>
        <path d="M0 90H200"/>
        <rect x="0" y="0" width="200" height="100"/>
        <g><title>north  wall</title><path d="M5 5h10v2h-10z"/></g>"##;
    if let Err(m) = check(before, after) {
        panic!("{m}");
    }
    // Rounding to a tenth of a pixel on one side, to a millimetre at 100 px/m on
    // the other.
    assert!(check(
        r#"<circle cx="12.3" cy="45.7" r="2"/>"#,
        r#"<g transform="scale(100)"><circle cx="0.123" cy="0.456" r="0.02"/></g>"#
    )
    .is_ok());
}

#[test]
fn one_circle_moved_by_a_pixel_is_found_and_named() {
    let many = |moved: f64| {
        (0..200)
            .map(|i| {
                let dx = if i == 137 { moved } else { 0.0 };
                format!(
                    r#"<circle cx="{:.1}" cy="{:.1}" r="2.2"/>"#,
                    (i % 20) as f64 * 9.0 + dx,
                    (i / 20) as f64 * 9.0
                )
            })
            .collect::<String>()
    };
    let m = check(&many(0.0), &many(1.0)).unwrap_err();
    assert!(m.contains("test.svg"), "{m}");
    assert!(m.contains("circle: 200 in the reference, 200 now; 1 of the reference's without a match now, 1 of the new without a match"), "{m}");
    assert!(
        m.contains("only in the reference: circle at (153.00, 54.00) r 2.20"),
        "{m}"
    );
    assert!(
        m.contains("only now: circle at (154.00, 54.00) r 2.20"),
        "{m}"
    );
    assert!(m.contains("off by 1.00 px"), "{m}");
    assert!(!m.contains("line:"), "{m}");
}

#[test]
fn a_dropped_polyline_is_found() {
    let a =
        r#"<polyline points="1,1 2,2 3,3"/><polyline points="10,10 20,20"/><path d="M5 5L6 6"/>"#;
    let b = r#"<polyline points="1,1 2,2 3,3"/><path d="M5 5L6 6"/>"#;
    let m = check(a, b).unwrap_err();
    assert!(m.contains("line: 3 in the reference, 2 now; 1 of the reference's without a match now, 0 of the new"), "{m}");
    assert!(m.contains("only in the reference: line of 2 vertices: (10.00, 10.00) (20.00, 20.00) (<polyline> on line 1)"), "{m}");
    // A vertex more, a ring instead of an open line, or a changed text are differences too.
    assert!(check(a, r#"<polyline points="1,1 2,2 3,3 4,4"/><polyline points="10,10 20,20"/><path d="M5 5L6 6"/>"#).is_err());
    assert!(check(
        r#"<polyline points="1,1 2,2 3,1"/>"#,
        r#"<polygon points="1,1 2,2 3,1"/>"#
    )
    .is_err());
    assert!(check(
        r#"<text x="1" y="2">1.25 s</text>"#,
        r#"<text x="1" y="2">1.3 s</text>"#
    )
    .is_err());
    assert!(check(r#"<g><title>a</title></g>"#, r#"<g><title>b</title></g>"#).is_err());
}

#[test]
fn defs_clip_paths_and_patterns_draw_nothing_and_use_draws_its_target() {
    let s = svg(
        r##"<defs><pattern id="p"><rect width="6" height="6"/></pattern><circle id="dot" r="2"/></defs>
           <clipPath id="c"><rect x="1" y="1" width="5" height="5"/></clipPath>
           <use href="#dot" x="10" y="20"/>"##,
    );
    assert_eq!(s.len(), 1, "{s:?}");
    assert!(close(s[0].points[0], (10.0, 20.0)), "{s:?}");
}

#[test]
fn numbers_in_text_are_compared_as_numbers() {
    use svg_shapes::normalise_text;
    assert_eq!(normalise_text("  1.50 m,  x −0.000  "), "1.5 m, x 0");
    assert_eq!(
        normalise_text("arrived in 4.30 s; 97.3 % at 12"),
        "arrived in 4.3 s; 97.3 % at 12"
    );
    assert_eq!(
        normalise_text("0.12345 and -2.0 but a-1"),
        "0.123 and -2 but a-1"
    );
    assert_eq!(normalise_text("100–130 s, .5"), "100–130 s, 0.5");
}

#[test]
fn close_duplicates_are_matched_as_a_whole() {
    // Two circles about 0.1 px apart on each side: the first reference circle's
    // nearest partner (0.04 px) is the only one the second can have; the matching
    // gives it up for the other (0.10 px).
    let a = r#"<circle cx="10.12" cy="10" r="1"/><circle cx="10.00" cy="10" r="1"/>"#;
    let b = r#"<circle cx="10.22" cy="10" r="1"/><circle cx="10.08" cy="10" r="1"/>"#;
    if let Err(m) = check(a, b) {
        panic!("{m}");
    }
}

#[test]
fn a_large_picture_compares_quickly() {
    // 20,000 line vertices, 5,000 circles, 2,000 rects: about 400 kB of SVG.
    let mut body = String::new();
    for i in 0..2000 {
        let pts: Vec<String> = (0..10)
            .map(|k| {
                format!(
                    "{:.1},{:.1}",
                    (i % 50) as f64 * 4.0 + k as f64 * 0.3,
                    (i / 50) as f64 * 2.5 + k as f64 * 0.1
                )
            })
            .collect();
        body += &format!(r#"<polyline points="{}"/>"#, pts.join(" "));
        body += &format!(r#"<path d="M{} {}h1v1h-1z"/>"#, i % 50, i / 50);
    }
    for i in 0..5000 {
        body += &format!(
            r#"<circle cx="{:.1}" cy="{:.1}" r="1"/>"#,
            (i % 100) as f64 * 2.0,
            (i / 100) as f64 * 2.0
        );
    }
    let t = Instant::now();
    let (a, b) = (svg(&body), svg(&body));
    let mut reversed = b.clone();
    reversed.reverse();
    same_data("large.svg", &a, &reversed, TOLERANCE_PX).unwrap();
    let took = t.elapsed();
    assert_eq!(a.len(), 9000);
    eprintln!("9000 shapes read twice and compared in {}", ms(took));
}
