#![no_main]
//! Arbitrary `formations.shapes` lists: parsing and validation answer with a library
//! or located problems, never a panic; every accepted shape meshes at any placement
//! into a mesh that passes its own `sanity_check` (or a clear mesh error).
use crowdtouch::crowd::formation::{FormationDef, FormationLibrary, Placement};
use crowdtouch::geom::Vec2;
use crowdtouch::located::parse_strict;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(defs) = parse_strict::<Vec<FormationDef>>(text) else {
        return;
    };
    let Ok(lib) = FormationLibrary::with(&defs) else {
        return;
    };
    for d in &defs {
        let f = lib
            .get(&d.name)
            .expect("an accepted shape is in the library");
        let place = Placement {
            centre_m: Vec2::new(8.0, 4.5),
            heading: Vec2::new(0.3, -1.0),
            area_m2: 12.0,
        };
        if let Ok(m) = f.mesh(&place, 80) {
            m.sanity_check().expect("a formation mesh is consistent");
        }
    }
});
