//! The `transform` and `transform_end` messages: a running formation transform's
//! progress every tick and its summary when it ends, sent to clients subscribed to
//! `transform` only.
//!
//! ```text
//! {"type":"transform","seq":812,"formation":"ring","method":"transform","cost":"least_effort","progress":0.42,"elapsed_s":3.1,"I_d":1.73,"sigma_min_dis":0.021,"sigma_curr_eft":0.35,"min_distance_m":0.29,"overlapping_pairs":0,"subgroups":7,"agent_subgroups":[0,0,3,…],"speed_m_s":1.3}
//! {"type":"transform_end","formation":"ring","cost":"least_effort","outcome":"arrived","agents":200,…}
//! ```
//!
//! Non-finite numbers are written as `null`.

use crate::vocab::{TransformSummary, TransformView};
use serde::Serialize;

#[derive(Serialize)]
struct ProgressWire<'a> {
    #[serde(rename = "type")]
    ty: &'static str,
    seq: u64,
    formation: &'a str,
    method: &'static str,
    cost: &'static str,
    progress: f64,
    elapsed_s: f64,
    #[serde(rename = "I_d")]
    i_d: f64,
    sigma_min_dis: f64,
    sigma_curr_eft: f64,
    min_distance_m: f64,
    overlapping_pairs: u32,
    subgroups: u32,
    agent_subgroups: &'a [u32],
    speed_m_s: f64,
}

#[derive(Serialize)]
struct EndWire<'a> {
    #[serde(rename = "type")]
    ty: &'static str,
    formation: &'a str,
    cost: &'a str,
    outcome: &'static str,
    agents: u32,
    steps: u64,
    simulated_s: f64,
    arrived_fraction: f64,
    min_distance_m: f64,
    overlapping_pairs: u64,
    swaps: u64,
    mean_travel_m: f64,
    max_travel_m: f64,
    #[serde(rename = "I_d")]
    i_d: f64,
    sigma_min_dis: f64,
    sigma_curr_eft: f64,
    subgroups: u32,
    speed_m_s: f64,
}

/// Appends one `transform` line (a running transform's progress this tick).
pub fn encode_transform_json(v: &TransformView, out: &mut Vec<u8>) {
    let w = ProgressWire {
        ty: "transform",
        seq: v.seq,
        formation: &v.formation,
        method: v.method,
        cost: v.cost,
        progress: v.progress,
        elapsed_s: v.elapsed_s,
        i_d: v.measures.i_d,
        sigma_min_dis: v.measures.sigma_min_dis_m,
        sigma_curr_eft: v.measures.sigma_curr_eft_m,
        min_distance_m: v.min_distance_m,
        overlapping_pairs: v.overlapping_pairs,
        subgroups: v.subgroups,
        agent_subgroups: &v.agent_subgroups,
        speed_m_s: v.speed_m_s,
    };
    // Writing plain numbers and strings to a `Vec` cannot fail.
    let _ = serde_json::to_writer(&mut *out, &w);
    out.push(b'\n');
}

/// Appends one `transform_end` line (a transform ended; the measures are its
/// means over the run).
pub fn encode_transform_end_json(s: &TransformSummary, out: &mut Vec<u8>) {
    let w = EndWire {
        ty: "transform_end",
        formation: &s.formation,
        cost: &s.cost,
        outcome: s.outcome.as_str(),
        agents: s.agents,
        steps: s.steps,
        simulated_s: s.simulated_s,
        arrived_fraction: s.arrived_fraction,
        min_distance_m: s.min_distance_m,
        overlapping_pairs: s.overlapping_pairs,
        swaps: s.swaps,
        mean_travel_m: s.mean_travel_m,
        max_travel_m: s.max_travel_m,
        i_d: s.mean.i_d,
        sigma_min_dis: s.mean.sigma_min_dis_m,
        sigma_curr_eft: s.mean.sigma_curr_eft_m,
        subgroups: s.subgroups,
        speed_m_s: s.speed_m_s,
    };
    let _ = serde_json::to_writer(&mut *out, &w);
    out.push(b'\n');
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::{TransformMeasures, TransformOutcome};
    use std::sync::Arc;

    #[test]
    fn a_progress_line_is_json_with_every_field_and_null_for_nan() {
        let v = TransformView {
            formation: Arc::from("ring"),
            method: "transform",
            cost: "least_effort",
            seq: 7,
            progress: 0.25,
            elapsed_s: 1.5,
            measures: TransformMeasures {
                i_d: f64::NAN,
                sigma_min_dis_m: 0.02,
                sigma_curr_eft_m: 0.3,
            },
            min_distance_m: 0.29,
            overlapping_pairs: 2,
            subgroups: 5,
            agent_subgroups: Arc::new(vec![0, 4, 4, 1]),
            speed_m_s: 1.3,
        };
        let mut out = Vec::new();
        encode_transform_json(&v, &mut out);
        assert_eq!(out.last(), Some(&b'\n'));
        let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
        assert_eq!(j["type"], "transform");
        assert_eq!(j["formation"], "ring");
        assert_eq!(j["progress"], 0.25);
        assert_eq!(j["I_d"], serde_json::Value::Null);
        assert_eq!(j["sigma_min_dis"], 0.02);
        assert_eq!(j["overlapping_pairs"], 2);
        assert_eq!(j["subgroups"], 5);
        assert_eq!(j["agent_subgroups"], serde_json::json!([0, 4, 4, 1]));
    }

    #[test]
    fn an_end_line_says_how_it_ended() {
        let s = TransformSummary {
            formation: "arrow".into(),
            cost: "euclidean".into(),
            outcome: TransformOutcome::TimedOut,
            agents: 10,
            steps: 300,
            simulated_s: 5.0,
            arrived_fraction: 0.9,
            min_distance_m: 0.2,
            overlapping_pairs: 1,
            swaps: 2,
            mean_travel_m: 2.0,
            max_travel_m: 4.0,
            mean: TransformMeasures::default(),
            subgroups: 3,
            speed_m_s: 1.0,
        };
        let mut out = Vec::new();
        encode_transform_end_json(&s, &mut out);
        let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
        assert_eq!(j["type"], "transform_end");
        assert_eq!(j["outcome"], "timed_out");
        assert_eq!(j["steps"], 300);
        assert_eq!(j["arrived_fraction"], 0.9);
        assert_eq!(j["swaps"], 2);
    }
}
