//! The formation library: the shipped shapes (`config/formations/`, embedded in the
//! binary so nothing is read at run time) and the config's own, which add to them
//! or replace one of the same name.

use super::shapes::{FileReader, Formation, FormationDef, MAX_FORMATIONS, START};

/// The shipped shape files, `(file name, RON text)` of one [`FormationDef`] each,
/// in library order.
pub const SHIPPED: &[(&str, &str)] = &[
    (
        "square.ron",
        include_str!("../../../config/formations/square.ron"),
    ),
    (
        "arrow.ron",
        include_str!("../../../config/formations/arrow.ron"),
    ),
    (
        "column.ron",
        include_str!("../../../config/formations/column.ron"),
    ),
    (
        "line.ron",
        include_str!("../../../config/formations/line.ron"),
    ),
    (
        "wedge.ron",
        include_str!("../../../config/formations/wedge.ron"),
    ),
    (
        "diamond.ron",
        include_str!("../../../config/formations/diamond.ron"),
    ),
    (
        "circle.ron",
        include_str!("../../../config/formations/circle.ron"),
    ),
    (
        "ring.ron",
        include_str!("../../../config/formations/ring.ron"),
    ),
    (
        "two_groups.ron",
        include_str!("../../../config/formations/two_groups.ron"),
    ),
    (
        "letter_a.ron",
        include_str!("../../../config/formations/letter_a.ron"),
    ),
    (
        "heart.ron",
        include_str!("../../../config/formations/heart.ron"),
    ),
];

/// The images the shipped shapes name, `(file name, bytes)`.
pub const SHIPPED_IMAGES: &[(&str, &[u8])] = &[(
    "heart.png",
    include_bytes!("../../../config/formations/heart.png"),
)];

/// Reads a shipped image by its file name.
fn shipped_image(path: &str) -> Result<Vec<u8>, String> {
    SHIPPED_IMAGES
        .iter()
        .find(|(n, _)| *n == path)
        .map(|(_, b)| b.to_vec())
        .ok_or_else(|| format!("{path} is not a shipped image"))
}

/// The shipped definitions with their validated shapes.
///
/// # Errors
/// `(file, message)` of the first shipped file that does not parse or validate
/// (a build defect; tests check every shipped file).
pub fn shipped_formations() -> Result<Vec<Formation>, (String, String)> {
    SHIPPED
        .iter()
        .map(|(file, text)| {
            let def: FormationDef = ron::Options::default()
                .from_str(text)
                .map_err(|e| (file.to_string(), e.to_string()))?;
            Formation::from_def(&def, &shipped_image).map_err(|e| (file.to_string(), e.to_string()))
        })
        .collect()
}

/// The shapes a crowd can switch to: the shipped ones and the config's.
#[derive(Clone, Debug, PartialEq)]
pub struct FormationLibrary {
    formations: Vec<Formation>,
}

impl Default for FormationLibrary {
    fn default() -> Self {
        FormationLibrary::shipped()
    }
}

impl FormationLibrary {
    /// The shipped shapes ([`SHIPPED`]), parsed once per process.
    pub fn shipped() -> FormationLibrary {
        static LIB: std::sync::OnceLock<Vec<Formation>> = std::sync::OnceLock::new();
        let formations = LIB
            .get_or_init(|| match shipped_formations() {
                Ok(f) => f,
                // Every shipped file is checked by tests; reaching this is a build defect.
                Err((file, e)) => panic!("shipped formation {file} is invalid: {e}"),
            })
            .clone();
        FormationLibrary { formations }
    }

    /// [`FormationLibrary::with_files`] for polygon definitions: a bitmap
    /// definition is reported, as no file can be read.
    ///
    /// # Errors
    /// As [`FormationLibrary::with_files`].
    pub fn with(defs: &[FormationDef]) -> Result<FormationLibrary, Vec<(String, String)>> {
        FormationLibrary::with_files(defs, &|p| {
            Err(format!(
                "no file reader here to read {p} (load bitmaps through a config)"
            ))
        })
    }

    /// The shipped shapes plus `defs`, bitmaps read through `read` (given the path as
    /// written); a definition replaces a shipped shape of the same name.
    ///
    /// # Errors
    /// Every `(field, problem)` with `field` relative to the list (`[2].outline`):
    /// an invalid shape, a name given twice, more than [`MAX_FORMATIONS`]
    /// definitions (reported at the list itself, field `""`).
    pub fn with_files(
        defs: &[FormationDef],
        read: FileReader<'_>,
    ) -> Result<FormationLibrary, Vec<(String, String)>> {
        let mut lib = FormationLibrary::shipped();
        let mut problems = Vec::new();
        if defs.len() > MAX_FORMATIONS {
            problems.push((
                String::new(),
                format!(
                    "at most {MAX_FORMATIONS} formation shapes, got {}",
                    defs.len()
                ),
            ));
            return Err(problems);
        }
        for (i, d) in defs.iter().enumerate() {
            if defs[..i].iter().any(|e| e.name == d.name) {
                problems.push((
                    format!("[{i}].name"),
                    format!("formation `{}` is defined twice", d.name),
                ));
                continue;
            }
            match Formation::from_def(d, read) {
                Ok(f) => match lib.formations.iter_mut().find(|g| g.name() == f.name()) {
                    Some(g) => *g = f,
                    None => lib.formations.push(f),
                },
                Err(e) => {
                    let field = match e.field() {
                        "" => format!("[{i}]"),
                        f => format!("[{i}].{f}"),
                    };
                    problems.push((field, e.to_string()))
                }
            }
        }
        if problems.is_empty() {
            Ok(lib)
        } else {
            Err(problems)
        }
    }

    /// The formation named `name`.
    pub fn get(&self, name: &str) -> Option<&Formation> {
        self.formations.iter().find(|f| f.name() == name)
    }

    /// Names, shipped first, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> + '_ {
        self.formations.iter().map(|f| f.name())
    }

    /// Whether `name` is a known formation (a library name or [`START`]).
    pub fn knows(&self, name: &str) -> bool {
        name == START || self.get(name).is_some()
    }

    /// Every name a checkpoint or command may give: [`START`], then the library's.
    pub fn known_names(&self) -> Vec<&str> {
        std::iter::once(START).chain(self.names()).collect()
    }

    /// `start, square, arrow, …` for messages.
    pub fn names_list(&self) -> String {
        self.known_names().join(", ")
    }
}

/// The shipped `heart.png`'s pixels, `(width, height, grey)`: a heart (the curve
/// `(x² + y² − 1)³ − x² y³ ≤ 0`) in black on white, 96 × 96, tip down.
pub fn heart_pixels() -> (u32, u32, Vec<u8>) {
    let (w, h) = (96u32, 96u32);
    let mut grey = Vec::with_capacity((w * h) as usize);
    for r in 0..h {
        for c in 0..w {
            let x = (c as f64 + 0.5 - 48.0) / 36.0;
            let y = (48.0 - (r as f64 + 0.5)) / 36.0 + 0.1;
            let v = (x * x + y * y - 1.0).powi(3) - x * x * y.powi(3);
            grey.push(if v <= 0.0 { 0 } else { 255 });
        }
    }
    (w, h, grey)
}

#[cfg(test)]
mod tests {
    use super::super::shapes::Placement;
    use super::*;
    use crate::geom::Vec2;

    fn encode_heart() -> Vec<u8> {
        let (w, h, grey) = heart_pixels();
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, w, h);
            enc.set_color(png::ColorType::Grayscale);
            enc.set_depth(png::BitDepth::Eight);
            let mut wr = enc.write_header().unwrap();
            wr.write_image_data(&grey).unwrap();
        }
        out
    }

    /// Regenerates `config/formations/heart.png`: `cargo test --lib write_heart_png
    /// -- --ignored`.
    #[test]
    #[ignore]
    fn write_heart_png() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/config/formations/heart.png");
        std::fs::write(path, encode_heart()).unwrap();
    }

    #[test]
    fn the_library_adds_replaces_and_reports() {
        let star = FormationDef::polygon(
            "star",
            &[
                (1.0, 0.0),
                (0.2, 0.2),
                (0.0, 1.0),
                (-0.2, 0.2),
                (-1.0, 0.0),
                (-0.2, -0.2),
                (0.0, -1.0),
                (0.2, -0.2),
            ],
        );
        let sq = FormationDef::polygon("square", &[(0.0, 0.0), (3.0, 0.0), (3.0, 1.0), (0.0, 1.0)]);
        let lib = FormationLibrary::with(&[star.clone(), sq]).unwrap();
        assert!(lib.knows("star") && lib.knows("start") && !lib.knows("nope"));
        assert_eq!(lib.names().count(), SHIPPED.len() + 1);
        // The replaced square is 3:1 now.
        let o = lib.get("square").unwrap().outline();
        let w = o.iter().map(|p| p.x).fold(f64::MIN, f64::max)
            - o.iter().map(|p| p.x).fold(f64::MAX, f64::min);
        assert!((w - 3.0f64.sqrt()).abs() < 1e-12, "{w}");
        let m = lib
            .get("star")
            .unwrap()
            .mesh(
                &Placement {
                    centre_m: Vec2::new(3.0, 3.0),
                    heading: Vec2::new(1.0, 1.0),
                    area_m2: 5.0,
                },
                150,
            )
            .unwrap();
        m.sanity_check().unwrap();
        assert!((m.area() - 5.0).abs() < 1e-9);
        let e = FormationLibrary::with(&[
            star.clone(),
            FormationDef::polygon("x", &[(0.0, 0.0)]),
            star,
        ])
        .unwrap_err();
        assert_eq!(e.len(), 2);
        assert_eq!(e[0].0, "[1].outline");
        assert_eq!(e[1].0, "[2].name");
        assert!(e[1].1.contains("defined twice"), "{e:?}");
        assert!(lib.names_list().starts_with("start, square, arrow"));
    }

    #[test]
    fn the_shipped_heart_is_what_the_generator_draws() {
        let (w, h, grey) = heart_pixels();
        let img = super::super::bitmap::decode(SHIPPED_IMAGES[0].1).unwrap();
        assert_eq!((img.width, img.height), (w, h));
        let got: Vec<u8> = img.rgba.iter().map(|p| p[0]).collect();
        assert_eq!(got, grey);
    }

    #[test]
    fn every_shipped_file_loads_and_the_names_are_kept() {
        let f = shipped_formations().unwrap();
        let names: Vec<&str> = f.iter().map(|f| f.name()).collect();
        assert_eq!(
            names,
            [
                "square",
                "arrow",
                "column",
                "line",
                "wedge",
                "diamond",
                "circle",
                "ring",
                "two_groups",
                "letter_a",
                "heart"
            ]
        );
        let lib = FormationLibrary::shipped();
        assert_eq!(lib.get("ring").unwrap().pieces()[0].holes.len(), 1);
        assert_eq!(lib.get("two_groups").unwrap().pieces().len(), 2);
        assert_eq!(lib.get("letter_a").unwrap().pieces()[0].holes.len(), 1);
        assert!(lib.get("heart").unwrap().vertex_count() > 8);
        // Each shipped file sits in config/formations under its name.
        for (file, text) in SHIPPED {
            let on_disk = std::fs::read_to_string(format!(
                "{}/config/formations/{file}",
                env!("CARGO_MANIFEST_DIR")
            ))
            .unwrap();
            assert_eq!(&on_disk, text);
        }
    }
}
