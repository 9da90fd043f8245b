//! One row of the bench table: a workload's sample count, p50, p99, max and note.

use crowdtouch::vocab::StageStats;
use serde::Serialize;

#[derive(Serialize, Debug)]
pub(super) struct Row {
    pub(super) workload: String,
    pub(super) samples: u64,
    pub(super) p50_us: f64,
    pub(super) p99_us: f64,
    pub(super) max_us: f64,
    pub(super) note: String,
}

pub(super) fn quantiles(mut v: Vec<f64>) -> (f64, f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0, 0.0);
    }
    v.sort_by(f64::total_cmp);
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    (q(0.5), q(0.99), v[v.len() - 1])
}

pub(super) fn row_from_samples(name: &str, samples: Vec<f64>, note: String) -> Row {
    let n = samples.len() as u64;
    let (p50, p99, max) = quantiles(samples);
    Row {
        workload: name.into(),
        samples: n,
        p50_us: p50,
        p99_us: p99,
        max_us: max,
        note,
    }
}

pub(super) fn row_from_stage(name: &str, s: Option<&StageStats>, note: String) -> Row {
    let s = s.cloned().unwrap_or_default();
    Row {
        workload: name.into(),
        samples: s.count,
        p50_us: s.p50_us as f64,
        p99_us: s.p99_us as f64,
        max_us: s.max_us as f64,
        note,
    }
}
