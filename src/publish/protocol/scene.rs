//! The `scene` and `scene_poses` messages: the scene the crowd moves in (when it
//! changes, and to a client when it subscribes) and where its moving things are
//! (every tick while the scene has any), to clients subscribed to `scene` only.
//!
//! ```text
//! {"type":"scene","seq":1,"name":"street","bounds":[[0,0],[16,9]],
//!  "obstacles":[{"name":"west bollard","parts":[{"shape":"circle","centre":[6,6.6],"radius":0.15}]}],
//!  "patches":[{"name":"north kerb","motion":"climb_down","speed_factor":0.3,"parts":[{"shape":"polygon","points":[[6.2,6.6],…]}]}],
//!  "dynamic":[{"name":"bus","kind":"obstacle","parts":[…]}],
//!  "checkpoints":[{"name":"gate","formation":"ring","region":{"shape":"circle",…}}]}
//! {"type":"scene_poses","seq":812,"t_s":6.77,"poses":[[3.41,7.3,0.0],…]}
//! ```
//!
//! Metres and radians. A moving thing's parts are in its own frame; its pose
//! `[x, y, heading]` places them: `world = (x, y) + R(heading) · local`. Without a
//! scene, `name` is null and the lists are empty.

use crate::geom::Vec2;
use crate::vocab::{SceneItemView, ScenePoses, SceneView, ShapeView};
use serde::Serialize;

#[derive(Serialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
enum ShapeWire {
    Polygon { points: Vec<[f64; 2]> },
    Circle { centre: [f64; 2], radius: f64 },
}

fn xy(p: Vec2) -> [f64; 2] {
    [p.x, p.y]
}

fn shape(s: &ShapeView) -> ShapeWire {
    match s {
        ShapeView::Polygon(points) => ShapeWire::Polygon {
            points: points.iter().map(|&p| xy(p)).collect(),
        },
        ShapeView::Circle { centre, radius_m } => ShapeWire::Circle {
            centre: xy(*centre),
            radius: *radius_m,
        },
    }
}

#[derive(Serialize)]
struct ItemWire<'a> {
    name: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    kind: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    motion: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    speed_factor: Option<f64>,
    parts: Vec<ShapeWire>,
}

fn item(i: &SceneItemView, dynamic: bool) -> ItemWire<'_> {
    ItemWire {
        name: &i.name,
        kind: dynamic.then_some(if i.terrain.is_some() {
            "patch"
        } else {
            "obstacle"
        }),
        motion: i.terrain.map(|t| t.motion.as_str()),
        speed_factor: i.terrain.map(|t| t.speed_factor),
        parts: i.parts.iter().map(shape).collect(),
    }
}

#[derive(Serialize)]
struct CheckpointWire<'a> {
    name: &'a str,
    formation: &'a str,
    region: ShapeWire,
}

#[derive(Serialize)]
struct SceneWire<'a> {
    #[serde(rename = "type")]
    ty: &'static str,
    seq: u64,
    name: Option<&'a str>,
    bounds: [[f64; 2]; 2],
    obstacles: Vec<ItemWire<'a>>,
    patches: Vec<ItemWire<'a>>,
    dynamic: Vec<ItemWire<'a>>,
    checkpoints: Vec<CheckpointWire<'a>>,
}

/// Appends one `scene` line.
pub fn encode_scene_json(s: &SceneView, out: &mut Vec<u8>) {
    let w = SceneWire {
        ty: "scene",
        seq: s.seq,
        name: s.name.as_deref(),
        bounds: [s.bounds.min, s.bounds.max],
        obstacles: s.obstacles.iter().map(|i| item(i, false)).collect(),
        patches: s.patches.iter().map(|i| item(i, false)).collect(),
        dynamic: s.dynamic.iter().map(|i| item(i, true)).collect(),
        checkpoints: s
            .checkpoints
            .iter()
            .map(|c| CheckpointWire {
                name: &c.name,
                formation: &c.formation,
                region: shape(&c.region),
            })
            .collect(),
    };
    // Plain numbers (non-finite ones become null) and strings: cannot fail.
    let _ = serde_json::to_writer(&mut *out, &w);
    out.push(b'\n');
}

#[derive(Serialize)]
struct PosesWire<'a> {
    #[serde(rename = "type")]
    ty: &'static str,
    seq: u64,
    t_s: f64,
    poses: &'a [[f64; 3]],
}

/// Appends one `scene_poses` line. `scratch` keeps its capacity between calls.
pub fn encode_scene_poses_json(p: &ScenePoses, scratch: &mut Vec<[f64; 3]>, out: &mut Vec<u8>) {
    scratch.clear();
    scratch.extend(p.poses.iter().map(|(pos, h)| [pos.x, pos.y, *h]));
    let w = PosesWire {
        ty: "scene_poses",
        seq: p.seq,
        t_s: p.t_s,
        poses: scratch,
    };
    let _ = serde_json::to_writer(&mut *out, &w);
    out.push(b'\n');
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Rect;
    use crate::vocab::{CheckpointView, MotionType, TerrainView};

    fn scene() -> SceneView {
        SceneView {
            seq: 3,
            name: Some("street".into()),
            bounds: Rect {
                min: [0.0, 0.0],
                max: [16.0, 9.0],
            },
            obstacles: vec![SceneItemView {
                name: "bollard".into(),
                terrain: None,
                parts: vec![ShapeView::Circle {
                    centre: Vec2::new(6.0, 6.6),
                    radius_m: 0.15,
                }],
            }],
            patches: vec![SceneItemView {
                name: "kerb".into(),
                terrain: Some(TerrainView {
                    motion: MotionType::ClimbDown,
                    speed_factor: 0.3,
                }),
                parts: vec![ShapeView::Polygon(vec![
                    Vec2::new(0.0, 0.0),
                    Vec2::new(1.0, 0.0),
                    Vec2::new(1.0, 1.0),
                ])],
            }],
            dynamic: vec![SceneItemView {
                name: "bus".into(),
                terrain: None,
                parts: vec![],
            }],
            checkpoints: vec![CheckpointView {
                name: "gate".into(),
                formation: "ring".into(),
                region: ShapeView::Circle {
                    centre: Vec2::new(8.0, 2.0),
                    radius_m: 1.0,
                },
            }],
        }
    }

    #[test]
    fn a_scene_line_names_every_part_in_metres() {
        let mut out = Vec::new();
        encode_scene_json(&scene(), &mut out);
        assert_eq!(out.last(), Some(&b'\n'));
        let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
        assert_eq!(j["type"], "scene");
        assert_eq!(j["name"], "street");
        assert_eq!(j["bounds"], serde_json::json!([[0.0, 0.0], [16.0, 9.0]]));
        let bollard = &j["obstacles"][0];
        assert_eq!(bollard["parts"][0]["shape"], "circle");
        assert_eq!(bollard["parts"][0]["radius"], 0.15);
        assert!(bollard.get("kind").is_none() && bollard.get("motion").is_none());
        let kerb = &j["patches"][0];
        assert_eq!(kerb["motion"], "climb_down");
        assert_eq!(kerb["speed_factor"], 0.3);
        assert_eq!(kerb["parts"][0]["points"][2], serde_json::json!([1.0, 1.0]));
        assert_eq!(j["dynamic"][0]["kind"], "obstacle");
        assert_eq!(j["checkpoints"][0]["formation"], "ring");
        assert_eq!(
            j["checkpoints"][0]["region"]["centre"],
            serde_json::json!([8.0, 2.0])
        );
    }

    #[test]
    fn no_scene_is_a_null_name_and_empty_lists() {
        let s = SceneView {
            name: None,
            obstacles: vec![],
            patches: vec![],
            dynamic: vec![],
            checkpoints: vec![],
            ..scene()
        };
        let mut out = Vec::new();
        encode_scene_json(&s, &mut out);
        let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
        assert!(j["name"].is_null());
        assert_eq!(j["obstacles"], serde_json::json!([]));
    }

    #[test]
    fn poses_are_position_and_heading_triples() {
        let p = ScenePoses {
            seq: 9,
            t_s: 1.5,
            poses: vec![(Vec2::new(1.0, 2.0), 0.5), (Vec2::new(-3.0, 4.0), f64::NAN)],
        };
        let mut out = Vec::new();
        encode_scene_poses_json(&p, &mut Vec::new(), &mut out);
        let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
        assert_eq!(j["type"], "scene_poses");
        assert_eq!(j["seq"], 9);
        assert_eq!(j["poses"][0], serde_json::json!([1.0, 2.0, 0.5]));
        assert!(j["poses"][1][2].is_null());
    }
}
