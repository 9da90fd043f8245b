//! Properties every reader and writer share: what is written reads back to the same
//! tracks (on each format's grid: ETH times are video frames, CSV links come from
//! the frame step), and no text makes a reader panic or accept a set that breaks
//! [`TrackSet::validate`].

use super::*;
use crate::crowd::edit::tracks::{Track, TrackSet};
use crate::geom::Vec2;
use proptest::prelude::*;
use proptest::test_runner::{Config as ProptestConfig, RngSeed};

/// People as (id, start in steps, per later sample: steps after the previous one
/// (1 = linked, more = a gap), positions).
type People = Vec<(u64, u32, Vec<(u32, f64, f64)>, (f64, f64))>;

fn people() -> impl Strategy<Value = People> {
    // Any bit pattern within the readers' coordinate bound (±1e6 m).
    let coord = prop_oneof![
        -50.0f64..50.0,
        any::<f64>()
            .prop_filter("finite", |v| v.is_finite())
            .prop_map(|v| v % crate::crowd::edit::MAX_COORDINATE_M)
    ];
    let sample = (
        prop_oneof![3 => Just(1u32), 1 => 2u32..6],
        coord.clone(),
        coord.clone(),
    );
    prop::collection::btree_set(0u64..5000, 1..6).prop_flat_map(move |ids| {
        let n = ids.len();
        (
            Just(ids.into_iter().collect::<Vec<u64>>()),
            prop::collection::vec(
                (
                    0u32..30,
                    prop::collection::vec(sample.clone(), 0..8),
                    (coord.clone(), coord.clone()),
                ),
                n,
            ),
        )
            .prop_map(|(ids, rest)| {
                ids.into_iter()
                    .zip(rest)
                    .map(|(id, (start, samples, first))| (id, start, samples, first))
                    .collect()
            })
    })
}

/// The tracks of `people` with sample `k` steps from the start at time `time(k)`,
/// linked where one step apart.
fn tracks(people: &People, step_s: f64, time: impl Fn(u32) -> f64) -> TrackSet {
    let tracks = people
        .iter()
        .map(|(id, start, samples, first)| {
            let mut k = *start;
            let mut t = Track::linked(*id, vec![Vec2::new(first.0, first.1)], vec![time(k)]);
            for &(d, x, y) in samples {
                k += d;
                t.points.push(Vec2::new(x, y));
                t.times_s.push(time(k));
                t.linked.push(d == 1);
            }
            t
        })
        .collect();
    TrackSet { tracks, step_s }
}

/// `set` with its people in id order (readers keep the order of first appearance,
/// writers sort by time).
fn by_id(mut set: TrackSet) -> TrackSet {
    set.tracks.sort_by_key(|t| t.id);
    set
}

/// A reader's answer to any text: an error with a line inside the text, or a set
/// that passes validation.
fn check_answer(text: &str, r: Result<TrackSet, ReadError>) -> Result<(), TestCaseError> {
    match r {
        Ok(set) => prop_assert_eq!(set.validate(), Ok(())),
        Err(e) => prop_assert!(e.line <= text.lines().count(), "{}", e),
    }
    Ok(())
}

/// Text near a valid file: `base` with a stretch replaced by `noise`.
fn mutated(base: &str, at: usize, len: usize, noise: &str) -> String {
    let chars: Vec<char> = base.chars().collect();
    let at = at.min(chars.len());
    let end = (at + len).min(chars.len());
    let mut s: String = chars[..at].iter().collect();
    s.push_str(noise);
    s.extend(&chars[end..]);
    s
}

const SAMPLE_JSONL: &str = "{\"format\":\"crowdtouch-tracks\",\"version\":1,\"step_s\":0.4}\n\
    {\"id\":1,\"t_s\":0,\"x\":1.5,\"y\":2}\n{\"id\":2,\"t_s\":0,\"x\":3,\"y\":2}\n\
    {\"id\":1,\"t_s\":0.4,\"x\":1.75,\"y\":2,\"gap\":true}\n";
const SAMPLE_CSV: &str = "t,id,x,y\n0,1,1.5,2\n0,2,3,2\n0.4,1,1.75,2\n1.6,2,3.5,2\n";
const SAMPLE_ETH: &str = "0.0\t1.0\t1.5\t2.0\n0.0\t2.0\t3.0\t2.0\n10.0\t1.0\t1.75\t2.0\n";

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 128,
        rng_seed: RngSeed::Fixed(0x7472_6163),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn jsonl_reads_back_what_it_writes(p in people(), step in 1e-3f64..10.0,
                                       gaps in prop::collection::vec(any::<bool>(), 64)) {
        let mut set = tracks(&p, step, |k| f64::from(k) * step);
        // Links are free in JSON Lines: any sample may be a gap.
        for (j, l) in set.tracks.iter_mut().flat_map(|t| t.linked.iter_mut()).enumerate() {
            *l = !gaps[j % gaps.len()];
        }
        set.validate().unwrap();
        let again = read_jsonl(&write_jsonl(&set, Some("prop"))).unwrap();
        prop_assert_eq!(by_id(again), by_id(set));
    }

    #[test]
    fn csv_reads_back_what_it_writes(p in people(), step in 1e-3f64..10.0) {
        let set = tracks(&p, step, |k| f64::from(k) * step);
        set.validate().unwrap();
        let again = read_csv(&write_csv(&set), Some(step)).unwrap();
        prop_assert_eq!(by_id(again), by_id(set));
    }

    #[test]
    fn eth_reads_back_what_it_writes(p in people()) {
        let opts = EthOptions::default();
        let frames = f64::from(opts.frame_step);
        let set = tracks(&p, frames / opts.frame_rate_hz, |k| f64::from(k) * frames / opts.frame_rate_hz);
        set.validate().unwrap();
        let again = read_eth(&write_eth(&set, opts), opts).unwrap();
        prop_assert_eq!(by_id(again), by_id(set));
    }

    #[test]
    fn dispatch_reads_back_what_it_writes(p in people()) {
        let opts = ReadOptions { csv_step_s: Some(0.4), ..ReadOptions::default() };
        let set = tracks(&p, 0.4, |k| f64::from(k) * 10.0 / 25.0);
        for format in [Format::Jsonl, Format::Csv, Format::Eth] {
            let again = read(&write(&set, format, &opts), format, &opts).unwrap();
            prop_assert_eq!(by_id(again), by_id(set.clone()), "{:?}", format);
        }
    }

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC*", bytes in prop::collection::vec(any::<u8>(), 0..200)) {
        let lossy = String::from_utf8_lossy(&bytes).into_owned();
        for t in [text.as_str(), lossy.as_str()] {
            check_answer(t, read_jsonl(t))?;
            check_answer(t, read_csv(t, None))?;
            check_answer(t, read_eth(t, EthOptions::default()))?;
        }
    }

    #[test]
    fn text_near_valid_files_never_panics(at in 0usize..200, len in 0usize..8,
                                          noise in "[-0-9a-z.,:{}\\[\\]\"\\s eE+]{0,12}") {
        let t = mutated(SAMPLE_JSONL, at, len, &noise);
        check_answer(&t, read_jsonl(&t))?;
        let t = mutated(SAMPLE_CSV, at, len, &noise);
        check_answer(&t, read_csv(&t, None))?;
        let t = mutated(SAMPLE_ETH, at, len, &noise);
        check_answer(&t, read_eth(&t, EthOptions::default()))?;
    }
}

#[test]
fn the_samples_are_valid() {
    assert_eq!(read_jsonl(SAMPLE_JSONL).unwrap().samples(), 3);
    assert_eq!(read_csv(SAMPLE_CSV, None).unwrap().samples(), 4);
    assert_eq!(
        read_eth(SAMPLE_ETH, EthOptions::default())
            .unwrap()
            .samples(),
        3
    );
}

#[test]
fn formats_are_detected_from_extension_then_content() {
    use std::path::Path;
    assert_eq!(detect(Path::new("a.jsonl"), ""), Format::Jsonl);
    assert_eq!(detect(Path::new("a.CSV"), ""), Format::Csv);
    assert_eq!(detect(Path::new("a.txt"), "{"), Format::Eth);
    assert_eq!(detect(Path::new("a"), SAMPLE_JSONL), Format::Jsonl);
    assert_eq!(detect(Path::new("a"), SAMPLE_CSV), Format::Csv);
    assert_eq!(detect(Path::new("a"), SAMPLE_ETH), Format::Eth);
}
