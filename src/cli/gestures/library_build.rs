//! The generated libraries and test sets: `library build` (the simulator's crowd
//! motions with the gesture generators' gestures, as shipped) and `library
//! test-set`, and the mixture settings a config gives the build.

use crate::cli::common::output::outln;
use anyhow::{Context, Result};
use crowdtouch::config::Config;
use crowdtouch::crowd::motion::{build_library, BuildParams, FeatureParams};
use crowdtouch::gesture::generator::{draw_labelled, Generator};
use crowdtouch::gesture::library::{read_library, write_library, MotionClass};
use crowdtouch::gesture::synth::to_frames;
use crowdtouch::input::recording::JsonlWriter;
use crowdtouch::input::{AxisRange, SurfaceInfo};
use crowdtouch::vocab::Micros;
use std::path::Path;

/// `(gestures.gmm_components, gestures.auto_components_max)` of the config at
/// `path`, or the shipped library's `(2, None)`.
pub fn mixtures(path: Option<&Path>) -> Result<(usize, Option<usize>)> {
    Ok(match path {
        Some(p) => {
            let c = Config::load(p)?;
            (
                c.gestures.gmm_components as usize,
                c.gestures.auto_components_max.map(|k| k as usize),
            )
        }
        None => (2, None),
    })
}

pub fn build(
    out: &Path,
    seed: u64,
    classes: Vec<MotionClass>,
    (per_class, per_motion): (usize, usize),
    (gmm_components, auto_components): (usize, Option<usize>),
    generators: Vec<Generator>,
) -> Result<()> {
    let defaults = BuildParams::default();
    let p = BuildParams {
        seed,
        classes,
        motions_per_class: per_class,
        gestures_per_motion: per_motion,
        generators,
        features: FeatureParams {
            gmm_components,
            auto_components,
            ..defaults.features
        },
        ..defaults
    };
    let lib = build_library(&p)?;
    let bytes = write_library(&lib);
    // The file read back is the file written.
    read_library(&bytes, &out.display().to_string())?;
    std::fs::write(out, &bytes).with_context(|| format!("{}: cannot write", out.display()))?;
    outln!(
        "{}: {} motions, {} gestures, {} bytes",
        out.display(),
        lib.motions.len(),
        lib.gestures.len(),
        bytes.len()
    )?;
    Ok(())
}

pub fn test_set(out: &Path, seed: u64, per_class: usize, generator: Generator) -> Result<()> {
    let mut n = 0;
    for class in MotionClass::ALL {
        let dir = out.join(class.as_str());
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("{}: cannot create", dir.display()))?;
        for i in 0..per_class {
            let d = draw_labelled(generator, class, seed, i, None);
            let frames = to_frames(&d.tracks, d.device_mm, Micros(1_000_000));
            let surface = SurfaceInfo {
                name: format!(
                    "test set ({generator}) {:.0}x{:.0} mm",
                    d.device_mm.0, d.device_mm.1
                ),
                x: AxisRange {
                    min: 0.0,
                    max: d.device_mm.0 * 10.0,
                    resolution: 10.0,
                },
                y: AxisRange {
                    min: 0.0,
                    max: d.device_mm.1 * 10.0,
                    resolution: 10.0,
                },
                max_contacts: 10,
            };
            let path = dir.join(format!("{}-{i:02}.jsonl", class.as_str()));
            let file = std::fs::File::create(&path)
                .with_context(|| format!("{}: cannot create", path.display()))?;
            let mut w = JsonlWriter::new(&surface, std::io::BufWriter::new(file))?;
            for f in &frames {
                w.frame(f)?;
            }
            w.flush()?;
            n += 1;
        }
    }
    outln!(
        "{}: {n} gestures in {} classes",
        out.display(),
        MotionClass::ALL.len()
    )?;
    Ok(())
}
