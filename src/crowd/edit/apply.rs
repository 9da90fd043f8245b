//! Running an edit script ([`Script`]) on a track set: what `crowdtouch edit apply`
//! does, and what its report says.
//!
//! The script's operations run in order on one working set. `Select` makes the
//! selection the next operations act on; `Fix` holds the selected samples nearest
//! the places given; `Drag` builds the cage of the current selection on the tracks as
//! they are now (section 3.2), drags the handle nearest `from` (a cage vertex within
//! [`HANDLE_RADIUS_M`] unless a selected sample is nearer, else the nearest
//! selected sample) to `to` with the fixed
//! samples held (eq. 1, or eq. 6 with fixed points), writes the deformed samples
//! back and, unless told not to, corrects the speeds of the tracks it touched
//! (eq. 9); `Retime` drags the time node nearest `at_s` of every selected person
//! (section 3.3) with the nodes nearest `fixed_s` held. Every error names the line
//! of the operation at fault.

use super::cage::{correct_speeds, Cage, CageParams, Handle};
use super::error::EditError;
use super::script::{Op, Script, ScriptError, SelectSpec};
use super::select::{SampleRef, Selection, SelectionQuery};
use super::temporal::{retime, RetimeParams, TimeDrag};
use super::tracks::TrackSet;
use crate::geom::{Rect, Vec2};

/// A cage vertex this close to a drag's `from` is the handle (m); farther, the
/// nearest selected sample is.
pub const HANDLE_RADIUS_M: f64 = 0.25;

/// How a script runs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ApplyParams {
    /// The spatial editor's parameters (its `world` is set from [`Self::world`]).
    pub cage: CageParams,
    /// The temporal editor's.
    pub retime: RetimeParams,
    /// Drags must end inside this rectangle (m); `None`: anywhere.
    pub world: Option<Rect>,
}

/// What one drag did.
#[derive(Clone, Debug, PartialEq)]
pub struct DragReport {
    /// The script line.
    pub line: usize,
    /// The handle dragged, as text (`hull vertex 3`, `track 2 sample 14`).
    pub handle: String,
    /// How far it went (m).
    pub distance_m: f64,
    /// The cage's shape change ([`Cage::hull_shape_error`]): RMS relative change of
    /// the hull's edge lengths, and of its turning angles (rad).
    pub shape_edge_rms: f64,
    /// See `shape_edge_rms`.
    pub shape_angle_rms_rad: f64,
    /// Slowest and fastest segment speed after the drag relative to before, before
    /// the speed correction (eq. 9).
    pub speed_ratio_edited: (f64, f64),
    /// The same after the correction (`(1, 1)` when it was not asked for or nothing
    /// moved).
    pub speed_ratio_corrected: (f64, f64),
    /// The cage after the drag (m), counter-clockwise: with several time windows,
    /// the window holding the handle (`Cage::window_of`).
    pub hull: Vec<Vec2>,
    /// The cage before it (m).
    pub hull_rest: Vec<Vec2>,
    /// The deformation mesh's triangles over `mesh_vertices`.
    pub mesh_triangles: Vec<[u32; 3]>,
    /// The deformation mesh's vertices at rest (m).
    pub mesh_vertices: Vec<Vec2>,
}

/// What a script did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ApplyReport {
    /// Every drag, in order.
    pub drags: Vec<DragReport>,
    /// Retimes run.
    pub retimes: usize,
    /// Samples whose time a retime changed.
    pub retimed_samples: usize,
    /// The people the script touched (track indices, sorted).
    pub touched: Vec<usize>,
}

/// Runs `script` on `set`. On an error `set` holds the operations before the one at
/// fault.
///
/// # Errors
/// [`ScriptError::Op`] with the operation's line: an id the set does not hold, a
/// selection of fewer than 3 distinct places (no hull), a drag or fix with nothing
/// selected, a drag outside the world, a retiming that would reverse time.
pub fn run_script(
    set: &mut TrackSet,
    script: &Script,
    params: &ApplyParams,
) -> Result<ApplyReport, ScriptError> {
    let mut report = ApplyReport::default();
    let mut selection: Option<Selection> = None;
    let mut fixed_places: Vec<Vec2> = Vec::new();
    let cage_params = CageParams {
        world: params.world,
        ..params.cage
    };
    for (op, line) in &script.ops {
        let line = *line;
        let at = |e: EditError| ScriptError::Op {
            line,
            what: e.to_string(),
        };
        let need = |sel: &Option<Selection>| -> Result<Selection, ScriptError> {
            sel.clone().ok_or(ScriptError::Op {
                line,
                what: "nothing is selected: a Select must come first".into(),
            })
        };
        match op {
            Op::Select(spec) => {
                selection = Some(Selection::select(set, &query(spec)).map_err(at)?);
                fixed_places.clear();
            }
            Op::Fix(places) => {
                need(&selection)?;
                fixed_places.extend_from_slice(places);
            }
            Op::Unfix => fixed_places.clear(),
            Op::Drag {
                from,
                to,
                correct_speeds: correct,
            } => {
                let sel = need(&selection)?;
                let before = set.clone();
                let mut cage = Cage::new(set, &sel, &cage_params).map_err(at)?;
                // The nearer of a cage vertex within the radius and the nearest
                // selected sample: a sample under the finger is what it holds,
                // not a hull vertex beside it.
                let sample = nearest_sample(set, &sel, *from);
                let sample_d =
                    sample.map(|r| (set.tracks[r.track].points[r.sample] - *from).norm());
                let hull = cage.handle_near(*from, HANDLE_RADIUS_M).filter(|h| {
                    let d = cage
                        .handle_position(*h)
                        .map_or(f64::INFINITY, |q| (q - *from).norm());
                    sample_d.is_none_or(|s| d <= s)
                });
                let handle =
                    hull.or_else(|| sample.map(Handle::Sample))
                        .ok_or(ScriptError::Op {
                            line,
                            what: "nothing to drag near `from`".into(),
                        })?;
                let fixed: Vec<Handle> = fixed_places
                    .iter()
                    .filter_map(|&p| nearest_sample(set, &sel, p).map(Handle::Sample))
                    .filter(|h| *h != handle)
                    .collect();
                let start = cage.handle_position(handle).map_err(at)?;
                cage.drag(&[(handle, *to)], &fixed).map_err(at)?;
                cage.apply(set).map_err(at)?;
                let touched = sel.tracks();
                let speeds = if *correct {
                    let r = correct_speeds(&before, set, &touched).map_err(at)?;
                    (r.edited_ratio, r.corrected_ratio)
                } else {
                    let r = correct_speeds(&before, &mut set.clone(), &touched).map_err(at)?;
                    (r.edited_ratio, r.edited_ratio)
                };
                let shape = cage.hull_shape_error();
                // The cage drawn is the time window holding the handle.
                let win = cage.window(cage.window_of(handle).unwrap_or(0));
                report.drags.push(DragReport {
                    line,
                    handle: handle.to_string(),
                    distance_m: (*to - start).norm(),
                    shape_edge_rms: shape.edge_length_rms,
                    shape_angle_rms_rad: shape.angle_rms_rad,
                    speed_ratio_edited: speeds.0,
                    speed_ratio_corrected: speeds.1,
                    hull: win.deformed_hull(),
                    hull_rest: win.hull().to_vec(),
                    mesh_triangles: win.mesh_triangles().to_vec(),
                    mesh_vertices: win.mesh_vertices().to_vec(),
                });
                report.touched.extend(touched);
            }
            Op::Retime {
                at_s,
                to_s,
                fixed_s,
            } => {
                let sel = need(&selection)?;
                let tracks = sel.tracks();
                let first = *tracks.first().ok_or(ScriptError::Op {
                    line,
                    what: "nothing is selected".into(),
                })?;
                let node =
                    nearest_selected_node(set, &sel, first, *at_s).ok_or(ScriptError::Op {
                        line,
                        what: format!("no selected time node near {at_s} s"),
                    })?;
                let shift = to_s - at_s;
                let drag = TimeDrag {
                    node,
                    t_s: set.tracks[node.track].times_s[node.sample] + shift,
                };
                let mut fixed = Vec::new();
                for &k in &tracks {
                    for &f in fixed_s {
                        if let Some(n) = nearest_selected_node(set, &sel, k, f) {
                            if n != node {
                                fixed.push(n);
                            }
                        }
                    }
                }
                fixed.sort_unstable();
                fixed.dedup();
                let r = retime(set, &sel, &[drag], &fixed, &params.retime).map_err(at)?;
                report.retimes += 1;
                report.retimed_samples += r.moved;
                report.touched.extend(tracks);
            }
        }
    }
    report.touched.sort_unstable();
    report.touched.dedup();
    Ok(report)
}

fn query(s: &SelectSpec) -> SelectionQuery {
    SelectionQuery {
        ids: s.ids.clone(),
        rect: s.rect.map(|((x0, y0), (x1, y1))| Rect {
            min: [x0, y0],
            max: [x1, y1],
        }),
        lasso: s
            .lasso
            .as_ref()
            .map(|l| l.iter().map(|&(x, y)| Vec2::new(x, y)).collect()),
        window_s: s.time_s,
    }
}

/// The selected sample nearest `p`.
fn nearest_sample(set: &TrackSet, sel: &Selection, p: Vec2) -> Option<SampleRef> {
    sel.samples()
        .iter()
        .min_by(|a, b| {
            let da = (set.tracks[a.track].points[a.sample] - p).norm_squared();
            let db = (set.tracks[b.track].points[b.sample] - p).norm_squared();
            da.total_cmp(&db)
        })
        .copied()
}

/// The selected sample of track `k` nearest in time to `t_s`.
fn nearest_selected_node(set: &TrackSet, sel: &Selection, k: usize, t_s: f64) -> Option<SampleRef> {
    sel.samples()
        .iter()
        .filter(|r| r.track == k)
        .min_by(|a, b| {
            let da = (set.tracks[k].times_s[a.sample] - t_s).abs();
            let db = (set.tracks[k].times_s[b.sample] - t_s).abs();
            da.total_cmp(&db)
        })
        .copied()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::edit::script::parse_script;
    use crate::crowd::edit::tracks::Track;

    /// Ten people in two rows walking +x at 1 m/s for 10 s, sampled every 0.5 s.
    fn parade() -> TrackSet {
        let times: Vec<f64> = (0..=20).map(|k| k as f64 * 0.5).collect();
        let tracks = (0..10)
            .map(|i| {
                let p0 = Vec2::new((i % 5) as f64 * 0.8, (i / 5) as f64 * 0.8);
                Track::linked(
                    i as u64,
                    times.iter().map(|t| p0 + Vec2::new(*t, 0.0)).collect(),
                    times.clone(),
                )
            })
            .collect();
        TrackSet {
            tracks,
            step_s: 0.5,
        }
    }

    #[test]
    fn a_scripted_drag_moves_the_handle_exactly_and_corrects_speeds() {
        let mut set = parade();
        let before = set.clone();
        // Person 2's sample at t = 5 s is at (6.6, 0.0).
        let script = parse_script("(ops: [Select(ids: Some([0, 1, 2, 3, 4, 5, 6, 7, 8, 9])), Fix(at: [(0.0, 0.0)]), Drag(from: (6.6, 0.0), to: (6.6, -1.0))])").unwrap();
        let r = run_script(&mut set, &script, &ApplyParams::default()).unwrap();
        assert_eq!(r.drags.len(), 1);
        let d = &r.drags[0];
        let held = set.tracks[2].points[10];
        // The sample under the finger is the handle (a hull vertex 2.5 cm away
        // was taken before, and the sample went only near the target).
        assert_eq!(d.handle, "track 2 sample 10");
        assert!(
            (held - Vec2::new(6.6, -1.0)).norm() < 1e-6,
            "{held:?} {}",
            d.handle
        );
        assert!(
            (set.tracks[0].points[0] - before.tracks[0].points[0]).norm() < 1e-9,
            "the fixed sample stays"
        );
        // Eq. 9: speeds back to their pre-edit values within 1 %.
        assert!(
            d.speed_ratio_corrected.0 > 0.99 && d.speed_ratio_corrected.1 < 1.01,
            "{d:?}"
        );
        assert!(d.shape_edge_rms.is_finite());
    }

    #[test]
    fn errors_name_the_operation_line() {
        let mut set = parade();
        let cases = [
            (
                "(ops: [\n Select(ids: Some([1, 99])),\n])",
                2,
                "unknown person id 99",
            ),
            (
                "(ops: [\n Drag(from: (0.0, 0.0), to: (1.0, 1.0)),\n])",
                2,
                "Select must come first",
            ),
            (
                "(ops: [\n Select(rect: Some(((100.0, 100.0), (101.0, 101.0)))),\n])",
                2,
                "no hull",
            ),
        ];
        let params = ApplyParams {
            world: Some(Rect {
                min: [-5.0, -5.0],
                max: [20.0, 20.0],
            }),
            ..ApplyParams::default()
        };
        for (text, line, what) in cases {
            let script = parse_script(text).unwrap();
            match run_script(&mut set, &script, &params) {
                Err(ScriptError::Op { line: l, what: w }) => {
                    assert_eq!(l, line, "{text}: {w}");
                    assert!(w.contains(what), "{text}: {w}");
                }
                other => panic!("{text}: expected an error, got {other:?}"),
            }
        }
        // A single person walking has many distinct places: a drag of one
        // person's samples is valid and moves the sample under the finger.
        let one = parse_script(
            "(ops: [\n Select(ids: Some([1])),\n Drag(from: (0.8, 0.0), to: (1.0, 1.0)),\n])",
        )
        .unwrap();
        let mut single = parade();
        let r = run_script(&mut single, &one, &params).unwrap();
        assert_eq!(r.drags.len(), 1);
        assert!((single.tracks[1].points[0] - Vec2::new(1.0, 1.0)).norm() < 1e-6);
        let outside = parse_script(
            "(ops: [\n Select(ids: Some([1, 2])),\n Drag(from: (1.0, 0.0), to: (50.0, 0.0)),\n])",
        )
        .unwrap();
        let e = run_script(&mut set, &outside, &params).unwrap_err();
        assert!(
            e.to_string().starts_with("line 3:") && e.to_string().contains("outside the world"),
            "{e}"
        );
    }

    #[test]
    fn a_scripted_retime_moves_the_node_and_keeps_the_places() {
        let mut set = parade();
        let before = set.clone();
        let script = parse_script("(ops: [Select(ids: Some([0, 1])), Retime(at_s: 5.0, to_s: 6.0, fixed_s: [0.0, 10.0])])").unwrap();
        let r = run_script(&mut set, &script, &ApplyParams::default()).unwrap();
        assert_eq!(r.retimes, 1);
        for k in [0, 1] {
            assert!(
                (set.tracks[k].times_s[10] - 6.0).abs() < 1e-9,
                "{:?}",
                set.tracks[k].times_s
            );
            assert_eq!(set.tracks[k].times_s[0], 0.0);
            assert_eq!(set.tracks[k].times_s[20], 10.0);
            assert_eq!(set.tracks[k].points, before.tracks[k].points);
        }
        assert_eq!(
            set.tracks[5], before.tracks[5],
            "people not selected keep their times"
        );
    }
}
