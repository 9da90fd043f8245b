#![no_main]
//! Edit scripts (`edit apply --ops`) into `parse_script`, and an accepted script run
//! by `run_script` on a small parade: an error names a line of the input (or line 0
//! for the whole file), never a panic; a script that runs leaves a track set that
//! passes `validate`.
use crowdtouch::crowd::edit::{parse_script, run_script, ApplyParams, ScriptError, Track, TrackSet};
use crowdtouch::geom::{Rect, Vec2};
use libfuzzer_sys::fuzz_target;

fn parade() -> TrackSet {
    let times: Vec<f64> = (0..=10).map(|k| k as f64 * 0.5).collect();
    let tracks = (0..6u64)
        .map(|i| {
            let p0 = Vec2::new((i % 3) as f64, (i / 3) as f64);
            Track::linked(i, times.iter().map(|t| p0 + Vec2::new(*t, 0.0)).collect(), times.clone())
        })
        .collect();
    TrackSet { tracks, step_s: 0.5 }
}

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let lines = text.lines().count().max(1);
    match parse_script(&text) {
        Err(ScriptError::Syntax(i)) => assert!(i.line <= lines + 1, "{i}"),
        Err(ScriptError::Op { line, .. }) => assert!(line <= lines, "line {line}"),
        Ok(script) => {
            let mut set = parade();
            let params = ApplyParams { world: Some(Rect { min: [-20.0, -20.0], max: [30.0, 30.0] }), ..ApplyParams::default() };
            match run_script(&mut set, &script, &params) {
                Err(ScriptError::Op { line, .. }) => assert!(line <= lines, "line {line}"),
                Err(ScriptError::Syntax(i)) => panic!("a run reports no syntax error: {i}"),
                Ok(_) => set.validate().expect("an edited set is valid"),
            }
        }
    }
});
