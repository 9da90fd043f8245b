#![no_main]
//! Arbitrary bytes as a formation image (PNG or PGM) with a colour range taken from
//! the first bytes: decoding, eq. 1 selection, tracing and validation answer with a
//! formation or a named error, never a panic; an accepted one meshes into a mesh
//! that passes its own `sanity_check` (or a clear mesh error) and samples exactly
//! the asked count.
use crowdtouch::crowd::formation::{BitmapDef, Formation, Placement, SampleParams};
use crowdtouch::geom::Vec2;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 7 {
        return;
    }
    let (head, bytes) = data.split_at(6);
    let def = BitmapDef {
        path: "fuzz.img".into(),
        c_min: (head[0], head[1], head[2]),
        c_max: (head[3], head[4], head[5]),
        size_m: None,
    };
    let Ok(f) = Formation::from_bitmap("fuzz", bytes, &def) else {
        return;
    };
    let place = Placement {
        centre_m: Vec2::new(8.0, 4.5),
        heading: Vec2::new(0.3, -1.0),
        area_m2: 12.0,
    };
    if let Ok(m) = f.mesh(&place, 80) {
        m.sanity_check().expect("a formation mesh is consistent");
    }
    let p = SampleParams {
        min_spacing_m: 0.3,
        relax_iterations: 5,
    };
    if let Ok(Some(pts)) = f.sample(&place, 20, &p, 1, &|| false) {
        assert_eq!(pts.len(), 20);
    }
});
