#![no_main]
//! Arbitrary scene files: `Scene::from_str` answers with a scene or located errors,
//! never a panic; an accepted scene passes its own `sanity_check`, and its geometry
//! queries (projection out of obstacles, terrain lookup) stay finite.
use crowdtouch::crowd::environment::Scene;
use crowdtouch::geom::Vec2;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(scene) = Scene::from_str(text, Path::new("fuzz.ron"), 0.15) else {
        return;
    };
    scene
        .sanity_check()
        .expect("an accepted scene is consistent");
    for k in 0..16 {
        let p = Vec2::new(f64::from(k) * 1.1 - 2.0, f64::from(k % 5) * 2.3 - 1.0);
        let q = scene.project_out(p, 0.15, 0.0);
        assert!(q.x.is_finite() && q.y.is_finite());
        let _ = scene.terrain_at(q, 0.0);
    }
});
