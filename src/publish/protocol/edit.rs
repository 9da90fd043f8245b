//! The edit mode's messages (crowd-motion-editing), to clients subscribed to `edit`:
//! `tracks` when the tracks change (every person after a load, an undo or a
//! finished edit, with their times; only the people a drag changes while fingers
//! hold them, places only, at most every 100 ms) and
//! `edit` when the edit's state changes (the selection's cage, the collisions).
//!
//! ```text
//! {"type":"tracks","version":3,"source":"parade.jsonl","full":true,"span_s":[0.0,42.0],"preview":false,"tracks":[{"id":1,"points":[[1.0,2.0],…],"times_s":[0.0,0.4,…]},…]}
//! {"type":"edit","seq":812,"version":3,"state":"grabbed","play_t_s":12.4,"selected":[1,2,5],"hull":[[0.5,1.0],…],"threshold_m":0.3,"undo_depth":1,"collisions":[{"a":1,"b":5,"t_s":14.2,"x":3.1,"y":4.0,"distance_m":0.21}],"pins":[[2.8,2.0]],"handles":[[4.1,3.3]],"selection":{"ids":[],"window_s":null,"lasso":null},"preview":null}
//! ```
//!
//! After a release or a retime the result is a preview (`state: "preview"`, a
//! `tracks` message with `preview: true`, and in `edit` a `preview` object with
//! the people retimed and pushed and the pairs and closest distances before and
//! after collision avoidance) until `edit.accept` or `edit.undo`.
//!
//! Places are written to the millimetre, times to 0.1 ms; non-finite numbers as `null`.

use crate::vocab::{EditView, TracksView};
use serde::ser::{SerializeSeq, Serializer};
use serde::Serialize;

/// Places on the wire: to the millimetre.
struct Points<'a>(&'a [crate::geom::Vec2]);

impl Serialize for Points<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.0.len()))?;
        for p in self.0 {
            seq.serialize_element(&[round_to(p.x, 1e3), round_to(p.y, 1e3)])?;
        }
        seq.end()
    }
}

/// Times on the wire: to the tenth of a millisecond.
struct Times<'a>(&'a [f64]);

impl Serialize for Times<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.0.len()))?;
        for t in self.0 {
            seq.serialize_element(&round_to(*t, 1e4))?;
        }
        seq.end()
    }
}

/// `v` rounded to `1 / per` (non-finite values are left for the encoder's `null`).
fn round_to(v: f64, per: f64) -> f64 {
    if v.is_finite() {
        (v * per).round() / per
    } else {
        v
    }
}

#[derive(Serialize)]
struct TrackWire<'a> {
    id: u64,
    points: Points<'a>,
    #[serde(skip_serializing_if = "is_empty")]
    times_s: Times<'a>,
}

fn is_empty(t: &Times<'_>) -> bool {
    t.0.is_empty()
}

#[derive(Serialize)]
struct TracksWire<'a> {
    #[serde(rename = "type")]
    ty: &'static str,
    version: u64,
    source: &'a str,
    full: bool,
    span_s: [f64; 2],
    preview: bool,
    tracks: Vec<TrackWire<'a>>,
}

#[derive(Serialize)]
struct CollisionWire {
    a: u64,
    b: u64,
    t_s: f64,
    x: f64,
    y: f64,
    distance_m: f64,
}

#[derive(Serialize)]
struct EditWire<'a> {
    #[serde(rename = "type")]
    ty: &'static str,
    seq: u64,
    version: u64,
    state: &'static str,
    play_t_s: f64,
    selected: &'a [u64],
    hull: Points<'a>,
    threshold_m: f64,
    undo_depth: u32,
    collisions: Vec<CollisionWire>,
    pins: Points<'a>,
    handles: Points<'a>,
    selection: SelectionWire<'a>,
    preview: Option<PreviewWire<'a>>,
}

#[derive(Serialize)]
struct SelectionWire<'a> {
    ids: &'a [u64],
    window_s: Option<[f64; 2]>,
    lasso: Option<Points<'a>>,
}

#[derive(Serialize)]
struct PreviewWire<'a> {
    retimed: &'a [u64],
    pushed: &'a [u64],
    pairs_before: usize,
    pairs_after: usize,
    closest_before_m: Option<f64>,
    closest_after_m: Option<f64>,
}

/// Appends one `tracks` line.
pub fn encode_tracks_json(v: &TracksView, out: &mut Vec<u8>) {
    let w = TracksWire {
        ty: "tracks",
        version: v.version,
        source: &v.source,
        full: v.full,
        span_s: [v.span_s.0, v.span_s.1],
        preview: v.preview,
        tracks: v
            .tracks
            .iter()
            .map(|t| TrackWire {
                id: t.id,
                points: Points(&t.points),
                times_s: Times(&t.times_s),
            })
            .collect(),
    };
    // Writing plain numbers and strings to a `Vec` cannot fail.
    let _ = serde_json::to_writer(&mut *out, &w);
    out.push(b'\n');
}

/// Appends one `edit` line.
pub fn encode_edit_json(v: &EditView, out: &mut Vec<u8>) {
    let w = EditWire {
        ty: "edit",
        seq: v.seq,
        version: v.version,
        state: v.state,
        play_t_s: v.play_t_s,
        selected: &v.selected,
        hull: Points(&v.hull),
        threshold_m: v.threshold_m,
        undo_depth: v.undo_depth,
        collisions: v
            .collisions
            .iter()
            .map(|c| CollisionWire {
                a: c.a,
                b: c.b,
                t_s: c.t_s,
                x: c.place.x,
                y: c.place.y,
                distance_m: c.distance_m,
            })
            .collect(),
        pins: Points(&v.pins),
        handles: Points(&v.handles),
        selection: SelectionWire {
            ids: &v.selection.ids,
            window_s: v.selection.window_s.map(|(a, b)| [a, b]),
            lasso: v.selection.lasso.as_deref().map(Points),
        },
        preview: v.preview.as_ref().map(|p| PreviewWire {
            retimed: &p.retimed,
            pushed: &p.pushed,
            pairs_before: p.pairs_before,
            pairs_after: p.pairs_after,
            closest_before_m: p.closest_before_m.map(|d| round_to(d, 1e4)),
            closest_after_m: p.closest_after_m.map(|d| round_to(d, 1e4)),
        }),
    };
    let _ = serde_json::to_writer(&mut *out, &w);
    out.push(b'\n');
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;
    use crate::vocab::{CollisionView, TrackView};
    use std::sync::Arc;

    #[test]
    fn tracks_and_edit_lines_are_json_a_renderer_reads() {
        let v = TracksView {
            version: 3,
            source: Arc::from("a.jsonl"),
            tracks: vec![TrackView {
                id: 7,
                points: vec![Vec2::new(1.0, 2.0), Vec2::new(1.5, 2.0)],
                times_s: vec![0.0, 0.4],
            }],
            full: true,
            span_s: (0.0, 0.4),
            preview: true,
        };
        let mut out = Vec::new();
        encode_tracks_json(&v, &mut out);
        let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
        assert_eq!(j["type"], "tracks");
        assert_eq!(j["tracks"][0]["points"][1][0], 1.5);
        assert_eq!(j["tracks"][0]["times_s"][1], 0.4);
        let e = EditView {
            seq: 5,
            version: 3,
            state: "grabbed",
            play_t_s: 1.0,
            selected: vec![7],
            hull: vec![Vec2::new(0.0, 0.0); 3],
            collisions: vec![CollisionView {
                a: 7,
                b: 9,
                t_s: 2.0,
                place: Vec2::new(1.0, 1.0),
                distance_m: f64::NAN,
            }],
            threshold_m: 0.3,
            undo_depth: 1,
            pins: vec![Vec2::new(2.0, 3.0)],
            handles: vec![Vec2::new(4.0, 5.0)],
            selection: crate::vocab::SelectionView {
                ids: vec![7, 9],
                window_s: Some((1.0, 2.5)),
                lasso: None,
            },
            preview: Some(crate::vocab::PreviewView {
                retimed: vec![9],
                pushed: vec![],
                pairs_before: 2,
                pairs_after: 0,
                closest_before_m: Some(0.12345678),
                closest_after_m: None,
            }),
        };
        out.clear();
        encode_edit_json(&e, &mut out);
        let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
        assert_eq!(j["state"], "grabbed");
        assert_eq!(j["collisions"][0]["b"], 9);
        assert!(j["collisions"][0]["distance_m"].is_null());
        assert_eq!(j["pins"][0][1], 3.0);
        assert_eq!(j["handles"][0][0], 4.0);
        assert_eq!(j["selection"]["ids"][1], 9);
        assert_eq!(j["selection"]["window_s"][1], 2.5);
        assert!(j["selection"]["lasso"].is_null());
        assert_eq!(j["preview"]["retimed"][0], 9);
        assert_eq!(j["preview"]["pairs_before"], 2);
        assert_eq!(j["preview"]["closest_before_m"], 0.1235);
        assert!(j["preview"]["closest_after_m"].is_null());
        out.clear();
        encode_tracks_json(&v, &mut out);
        let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
        assert_eq!(j["preview"], true);
    }
}
