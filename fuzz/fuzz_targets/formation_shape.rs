#![no_main]
//! Arbitrary RON text as one formation definition (outline, holes, pieces):
//! parsing and validation answer with a formation or a named error, never a panic;
//! an accepted one meshes into a mesh that passes its own `sanity_check` (or a
//! clear mesh error) and samples exactly the asked count inside it.
use crowdtouch::crowd::formation::{Formation, FormationDef, Placement, SampleParams};
use crowdtouch::geom::Vec2;
use crowdtouch::located::parse_strict;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(def) = parse_strict::<FormationDef>(text) else {
        return;
    };
    let Ok(f) = Formation::new(&def) else {
        return;
    };
    let place = Placement {
        centre_m: Vec2::new(-3.0, 2.0),
        heading: Vec2::new(1.0, 1.0),
        area_m2: 20.0,
    };
    if let Ok(m) = f.mesh(&place, 120) {
        m.sanity_check().expect("a formation mesh is consistent");
    }
    let p = SampleParams {
        min_spacing_m: 0.3,
        relax_iterations: 5,
    };
    if let Ok(Some(pts)) = f.sample(&place, 30, &p, 2, &|| false) {
        assert_eq!(pts.len(), 30);
    }
});
