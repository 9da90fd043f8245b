//! The scene as the outputs see it: a [`SceneView`] when the scene changes, and
//! every tick while the scene has moving things, their [`ScenePoses`].

use super::state::Engine;
use crate::crowd::environment::{DynamicKind, Part, Terrain};
use crate::vocab::{CheckpointView, SceneItemView, ScenePoses, SceneView, ShapeView, TerrainView};
use std::sync::Arc;

fn shape(p: &Part) -> ShapeView {
    match p {
        Part::Polygon(poly) => ShapeView::Polygon(poly.vertices().to_vec()),
        Part::Circle(c) => ShapeView::Circle {
            centre: c.centre,
            radius_m: c.radius_m,
        },
    }
}

/// An obstacle (no terrain) or a patch as published.
fn item(name: &str, terrain: Option<Terrain>, parts: &[Part]) -> SceneItemView {
    SceneItemView {
        name: name.to_owned(),
        terrain: terrain.map(|t| TerrainView {
            motion: t.motion,
            speed_factor: t.speed_factor,
        }),
        parts: parts.iter().map(shape).collect(),
    }
}

impl Engine {
    /// The scene now, as published (`name` `None` without a scene).
    pub fn scene_view(&self) -> SceneView {
        let Some(s) = &self.scene else {
            return SceneView {
                seq: self.seq,
                name: None,
                bounds: self.world,
                obstacles: Vec::new(),
                patches: Vec::new(),
                dynamic: Vec::new(),
                checkpoints: Vec::new(),
            };
        };
        SceneView {
            seq: self.seq,
            name: Some(s.name().to_owned()),
            bounds: s.bounds(),
            obstacles: s
                .obstacles()
                .iter()
                .map(|o| item(&o.name, None, &o.parts))
                .collect(),
            patches: s
                .patches()
                .iter()
                .map(|p| item(&p.name, Some(p.terrain), &p.parts))
                .collect(),
            dynamic: s
                .dynamic()
                .iter()
                .map(|d| {
                    let terrain = match d.kind {
                        DynamicKind::Obstacle => None,
                        DynamicKind::Patch(t) => Some(t),
                    };
                    item(&d.name, terrain, &d.parts)
                })
                .collect(),
            checkpoints: s
                .checkpoints()
                .iter()
                .map(|c| CheckpointView {
                    name: c.name.clone(),
                    formation: c.formation.clone(),
                    region: shape(&c.region),
                })
                .collect(),
        }
    }

    /// The scene, when it changed since the last call (the first call always has it).
    pub(super) fn take_scene_view(&mut self) -> Option<Arc<SceneView>> {
        if !std::mem::take(&mut self.scene_out.changed) {
            return None;
        }
        Some(Arc::new(self.scene_view()))
    }

    /// Where the scene's moving things are at this tick's scene time, when it has
    /// any (a recycled `Arc`: no allocation once the pool is warm).
    pub(super) fn take_scene_poses(&mut self) -> Option<Arc<ScenePoses>> {
        let scene = self.scene.as_ref()?;
        if scene.dynamic().is_empty() {
            return None;
        }
        let t = self.scene_t_s;
        let mut poses = self.scene_out.poses.acquire();
        {
            let p = Arc::make_mut(&mut poses);
            p.seq = self.seq;
            p.t_s = t;
            p.poses.clear();
            p.poses.extend(scene.dynamic().iter().map(|d| {
                let placement = d.placement_at(t);
                (placement.position, placement.heading_rad())
            }));
        }
        self.scene_out.poses.keep(&poses);
        Some(poses)
    }
}
