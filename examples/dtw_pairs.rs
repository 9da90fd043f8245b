//! Writes random sequence pairs with crowdtouch's DTW and LB_Keogh values as JSON, for
//! `benches/dtw_crosscheck.py` to compare against the `dtaidistance` package.
//!
//! `cargo run --example dtw_pairs -- OUT.json`
//!
//! Each case: `a`, `b` (1-D: lists of numbers; 2-D: lists of `[x, y]`), `band`
//! (Sakoe–Chiba radius or null), `dtw` (ours) and, for 1-D equal lengths, `lb_keogh`
//! (ours: `a` against the envelope of `b`).

use crowdtouch::geom::Vec2;
use crowdtouch::gesture::dtw::{lb_keogh, Dtw, Envelope};
use crowdtouch::rng::SplitMix64;
use serde_json::{json, Value};

fn main() -> std::io::Result<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "dtw_pairs.json".to_string());
    let mut rng = SplitMix64::new(0xD7A1);
    let mut dtw = Dtw::new();
    let mut cases: Vec<Value> = Vec::new();
    for case in 0..400 {
        let n = 2 + (rng.next_u64() % 64) as usize;
        let m = if case % 2 == 0 {
            n
        } else {
            2 + (rng.next_u64() % 64) as usize
        };
        let band = if case % 3 == 0 {
            None
        } else {
            Some((rng.next_u64() % 12) as usize)
        };
        // A random walk, so warping has something to align.
        let mut walk = |len: usize| {
            let mut x = rng.uniform(-1.0, 1.0);
            (0..len)
                .map(|_| {
                    x += rng.uniform(-0.3, 0.3);
                    x
                })
                .collect::<Vec<f64>>()
        };
        if case % 4 < 2 {
            let (a, b) = (walk(n), walk(m));
            let d = dtw.distance(&a, &b, band, None);
            let lb = (n == m).then(|| lb_keogh(&a, &Envelope::of(&b, n, band), f64::INFINITY));
            cases.push(json!({ "dim": 1, "a": a, "b": b, "band": band, "dtw": d, "lb_keogh": lb }));
        } else {
            let (ax, ay, bx, by) = (walk(n), walk(n), walk(m), walk(m));
            let a: Vec<Vec2> = ax.iter().zip(&ay).map(|(&x, &y)| Vec2::new(x, y)).collect();
            let b: Vec<Vec2> = bx.iter().zip(&by).map(|(&x, &y)| Vec2::new(x, y)).collect();
            let d = dtw.distance(&a, &b, band, None);
            let pts = |v: &[Vec2]| v.iter().map(|p| vec![p.x, p.y]).collect::<Vec<_>>();
            cases.push(json!({ "dim": 2, "a": pts(&a), "b": pts(&b), "band": band, "dtw": d, "lb_keogh": null }));
        }
    }
    std::fs::write(&out, serde_json::to_vec(&cases)?)?;
    eprintln!("wrote {} cases to {out}", cases.len());
    Ok(())
}
