//! `crowdtouch edit check` on the UCY fixtures: the README's continuous counts, the
//! JSON report's fields, exit status 0 with collisions, and bad input as a clean
//! error.

use serde_json::Value;
use std::process::{Command, Output};

fn fixture(name: &str) -> String {
    format!("{}/tests/fixtures/crowd/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn check(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
        .args(["edit", "check"])
        .args(args)
        .output()
        .unwrap()
}

fn json_of(out: &Output) -> Value {
    assert!(
        out.status.success(),
        "status {:?}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn json_counts_agree_with_the_fixture_readme() {
    for (name, people, want, min) in [
        ("crowds_zara01.txt", 148, [3, 27], 0.236),
        ("students001.txt", 415, [168, 606], 0.078),
    ] {
        for (d, want) in ["0.3", "0.5"].iter().zip(want) {
            let v = json_of(&check(&[&fixture(name), "--threshold", d, "--json"]));
            assert_eq!(v["people"], people, "{name}");
            assert_eq!(v["pairs"], want, "{name} at {d}");
            assert_eq!(v["pair_list"].as_array().unwrap().len(), want);
            assert_eq!(
                v["threshold_m"].as_f64().unwrap(),
                d.parse::<f64>().unwrap()
            );
            assert!(v["samples"].as_u64().unwrap() > 0);
            let m = v["min_distance_m"].as_f64().unwrap();
            assert!((m - min).abs() < 5e-4, "{name}: {m}");
            let events = v["events"].as_array().unwrap();
            assert!(events.len() >= want);
            for e in events {
                for k in ["a", "b", "t_s", "x", "y", "distance_m"] {
                    assert!(!e[k].is_null(), "{k} in {e}");
                }
                assert!(e["distance_m"].as_f64().unwrap() < d.parse::<f64>().unwrap());
            }
        }
    }
}

#[test]
fn no_collision_is_a_null_minimum_and_exit_zero() {
    let v = json_of(&check(&[
        &fixture("crowds_zara01.txt"),
        "--threshold",
        "0.2",
        "--json",
    ]));
    assert_eq!(v["pairs"], 0);
    assert!(v["min_distance_m"].is_null());
    assert_eq!(v["events"].as_array().unwrap().len(), 0);
}

#[test]
fn text_report_names_the_counts() {
    let out = check(&[&fixture("students001.txt"), "--threshold", "0.2"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for want in [
        "people              415",
        "pairs in collision  48 closer than 0.2 m",
        "closest approach    0.078 m",
        "first events",
    ] {
        assert!(text.contains(want), "missing `{want}` in:\n{text}");
    }
}

#[test]
fn bad_threshold_and_missing_file_are_errors() {
    let out = check(&[&fixture("crowds_zara01.txt"), "--threshold", "0"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("threshold"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let out = check(&["/nonexistent/tracks.txt"]);
    assert_eq!(out.status.code(), Some(1));
}
