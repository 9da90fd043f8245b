use super::*;
use crate::gesture::library::{
    random_library, validate, validate_with, ClassNameError, RandomLibrarySpec,
};
use proptest::prelude::*;

const NAME: &str = "library.ctgl";

fn spec(motions: usize, gestures: usize) -> RandomLibrarySpec {
    RandomLibrarySpec {
        motions,
        gestures,
        components: 4,
        gmm_components: 2,
        max_fingers: 3,
    }
}

fn small() -> Library {
    random_library(&spec(10, 20), 7)
}

/// Offset of class `c`'s record in the file of `lib`.
fn class_offset(lib: &Library, c: usize) -> usize {
    HEADER_BYTES + lib.classes[..c].iter().map(|n| 4 + n.len()).sum::<usize>()
}

/// Offset of gesture `g`'s record in the file of `lib`.
fn gesture_offset(lib: &Library, g: usize) -> usize {
    class_offset(lib, lib.classes.len())
        + lib.motions.iter().map(motion_bytes).sum::<usize>()
        + lib.gestures[..g].iter().map(gesture_bytes).sum::<usize>()
}

/// `lib` in the version-1 layout (no class table: its classes must be the ten
/// built-in ones in order; no participant and device).
fn write_v1(lib: &Library) -> Vec<u8> {
    assert_eq!(lib.classes, MotionClass::all_names());
    let v2 = write_library(lib);
    let mut out = Vec::new();
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&1u32.to_le_bytes());
    put_u32(&mut out, lib.motions.len());
    put_u32(&mut out, lib.gestures.len());
    // Motion records are the same in both versions.
    let motions = class_offset(lib, lib.classes.len());
    let gestures = gesture_offset(lib, 0);
    out.extend_from_slice(&v2[motions..gestures]);
    for g in &lib.gestures {
        put_u32(&mut out, g.class.index());
        out.extend_from_slice(&g.motion.to_le_bytes());
        put_u32(&mut out, g.gesture.fingers.len());
        put_u32(&mut out, g.origin.len());
        for finger in &g.gesture.fingers {
            for p in finger {
                put_f64s(&mut out, &[p.x, p.y]);
            }
        }
        out.extend_from_slice(g.origin.as_bytes());
    }
    seal(&mut out);
    out
}

fn read_err(bytes: &[u8]) -> LibraryError {
    read_library(bytes, NAME).expect_err("the reader refuses it")
}

#[test]
fn crc32_matches_the_ieee_check_value() {
    // The CRC-32/IEEE check value of "123456789" (zlib.crc32 gives the same).
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    assert_eq!(crc32(b""), 0);
    // Eight bytes at a time and byte by byte agree on every length.
    let data: Vec<u8> = (0..100u32).map(|i| (i * 37 % 251) as u8).collect();
    for n in 0..data.len() {
        let mut crc = !0u32;
        for &b in &data[..n] {
            crc = CRC_TABLES[0][((crc ^ u32::from(b)) & 0xff) as usize] ^ (crc >> 8);
        }
        assert_eq!(crc32(&data[..n]), !crc, "length {n}");
    }
}

#[test]
fn a_random_library_is_valid_and_round_trips() {
    let lib = small();
    validate(&lib).expect("random libraries are valid");
    let bytes = write_library(&lib);
    assert_eq!(&bytes[..4], b"CTGL");
    assert_eq!(read_library(&bytes, NAME), Ok(lib));
}

#[test]
fn wrong_magic_and_version_are_named() {
    let mut bytes = write_library(&small());
    bytes[4] = 3;
    let e = read_err(&bytes).to_string();
    assert_eq!(
        e,
        "library.ctgl: offset 4: header: format version 3; this reader reads versions 1 to 2 (a newer crowdtouch wrote it, or it is damaged)"
    );
    bytes[4] = 0;
    assert!(read_err(&bytes).to_string().contains("format version 0;"));
    bytes[0] = b'X';
    let e = read_err(&bytes);
    assert!(matches!(e.problem, Problem::BadMagic { .. }), "{e}");
    assert!(e.to_string().contains("CTGL"), "{e}");
    let e = read_err(b"CT");
    assert!(matches!(e.problem, Problem::BadMagic { .. }), "{e}");
}

#[test]
fn every_truncation_is_refused() {
    let mut spec = spec(10, 10);
    spec.components = 2;
    let bytes = write_library(&random_library(&spec, 3));
    // Every length near both ends, and every 7th between (in full it is quadratic).
    let lengths = (0..bytes.len()).filter(|&n| n < 200 || n + 200 > bytes.len() || n % 7 == 0);
    for n in lengths {
        let e = read_err(&bytes[..n]);
        assert!(
            matches!(
                e.problem,
                Problem::Truncated { .. }
                    | Problem::BadMagic { .. }
                    | Problem::ChecksumMismatch { .. }
            ),
            "length {n}: {e}"
        );
    }
}

#[test]
fn trailing_bytes_are_refused() {
    let mut bytes = write_library(&small());
    let end = bytes.len();
    bytes.push(0);
    let e = read_err(&bytes);
    assert_eq!(e.problem, Problem::TrailingBytes { count: 1 });
    assert_eq!(e.offset, Some(end));
}

#[test]
fn a_huge_count_is_refused_before_allocating() {
    let mut bytes = write_library(&small());
    bytes[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    reseal(&mut bytes);
    let e = read_err(&bytes);
    assert!(
        matches!(e.problem, Problem::BadCount { what: "class", .. }),
        "{e}"
    );
    let mut bytes = write_library(&small());
    bytes[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    reseal(&mut bytes);
    let e = read_err(&bytes);
    assert!(
        matches!(
            e.problem,
            Problem::Truncated {
                what: "motions",
                ..
            }
        ),
        "{e}"
    );
    let mut bytes = write_library(&small());
    bytes[16..20].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = read_err(&bytes);
    assert!(
        matches!(
            e.problem,
            Problem::Truncated {
                what: "gestures",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn a_nan_names_gesture_finger_sample_and_offset() {
    let mut lib = small();
    lib.gestures[17]
        .gesture
        .fingers
        .push([Vec2::new(0.5, 0.5); T_H]);
    let f = lib.gestures[17].gesture.fingers.len() - 1;
    lib.gestures[17].gesture.fingers[f][5].x = f64::NAN;
    let bytes = write_library(&lib);
    let at = gesture_offset(&lib, 17) + GESTURE_HEAD_BYTES + f * FINGER_BYTES + 5 * 16;
    let e = read_err(&bytes);
    assert_eq!(
        e.to_string(),
        format!("library.ctgl: offset {at}: gesture 17: finger {f}: sample 5: x is NaN")
    );
    let e = validate(&lib).unwrap_err().to_string();
    assert_eq!(
        e,
        format!("(in memory): gesture 17: finger {f}: sample 5: x is NaN")
    );
}

#[test]
fn out_of_range_indices_are_refused() {
    let lib = small();
    let at = gesture_offset(&lib, 3);
    let mut bytes = write_library(&lib);
    bytes[at..at + 4].copy_from_slice(&10u32.to_le_bytes());
    reseal(&mut bytes);
    let e = read_err(&bytes);
    assert_eq!(
        (e.offset, &e.problem),
        (
            Some(at),
            &Problem::BadClass {
                index: 10,
                count: 10
            }
        )
    );
    let mut bytes = write_library(&lib);
    bytes[at + 4..at + 8].copy_from_slice(&10u32.to_le_bytes());
    reseal(&mut bytes);
    let e = read_err(&bytes);
    assert_eq!(
        e.problem,
        Problem::BadMotionIndex {
            index: 10,
            count: 10
        },
        "{e}"
    );
    // A motion of another class.
    let mut bytes = write_library(&lib);
    let other = (lib.gestures[3].motion + 1) % 10;
    bytes[at + 4..at + 8].copy_from_slice(&other.to_le_bytes());
    reseal(&mut bytes);
    assert!(matches!(
        read_err(&bytes).problem,
        Problem::ClassMismatch { .. }
    ));
    // Eleven fingers.
    let mut bytes = write_library(&lib);
    bytes[at + 8..at + 12].copy_from_slice(&11u32.to_le_bytes());
    reseal(&mut bytes);
    let e = read_err(&bytes);
    assert!(
        matches!(
            e.problem,
            Problem::BadCount {
                what: "finger",
                count: 11,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn motion_invariants_are_checked() {
    type Edit = fn(&mut MotionFeatures);
    let cases: [(Edit, &str); 7] = [
        (|m| m.gmm[0].weight *= 0.5, "weights sum to"),
        (|m| m.gmm[1].cov[1] += 0.5, "not symmetric"),
        (|m| m.gmm[0].cov[0] = -5.0, "not positive definite"),
        (|m| m.basis[2][7] += 0.01, "eigenvectors"),
        (|m| m.basis[1] = m.basis[0].clone(), "dot product"),
        (|m| m.duration_s = 0.0, "duration_s = 0"),
        (|m| m.gmm[1].mean[2] = f64::INFINITY, "mean[2] is inf"),
    ];
    for (edit, needle) in cases {
        let mut lib = small();
        edit(&mut lib.motions[4]);
        let e = read_err(&write_library(&lib)).to_string();
        assert!(
            e.starts_with("library.ctgl: offset ") && e.contains("motion 4"),
            "{e}"
        );
        assert!(e.contains(needle), "{needle}: {e}");
        assert!(validate(&lib).unwrap_err().to_string().contains(needle));
    }
}

#[test]
fn mismatched_dimensions_are_refused_in_memory() {
    let mut lib = small();
    lib.motions[2].mean.pop();
    assert!(validate(&lib)
        .unwrap_err()
        .to_string()
        .contains("mean has 127 values, expected 128"));
    let mut lib = small();
    lib.motions[2].gmm[0].cov.pop();
    let e = validate(&lib).unwrap_err();
    assert!(
        matches!(
            e.problem,
            Problem::DimensionMismatch {
                what: "covariance",
                ..
            }
        ),
        "{e}"
    );
    // The file then describes another layout: the reader refuses it too.
    assert!(read_library(&write_library(&lib), NAME).is_err());
    let mut lib = small();
    lib.motions[2].basis[1].push(0.0);
    assert!(validate(&lib).is_err());
    assert!(read_library(&write_library(&lib), NAME).is_err());
}

#[test]
fn empty_and_partial_libraries_follow_the_policy() {
    let empty = Library::default();
    let e = read_err(&write_library(&empty));
    assert_eq!(e.problem, Problem::NoClasses);
    assert_eq!(
        e.to_string(),
        "library.ctgl: offset 20: library: the library has no class"
    );
    assert_eq!(
        read_library_with(&write_library(&empty), NAME, LoadPolicy::Partial),
        Ok(empty.clone())
    );
    let named = Library::with_classes(vec!["wave".into(), "crossing".into()]);
    let e = read_err(&write_library(&named));
    assert_eq!(
        e.problem,
        Problem::Empty {
            motions: 0,
            gestures: 0
        }
    );
    assert_eq!(
        read_library_with(&write_library(&named), NAME, LoadPolicy::Partial),
        Ok(named)
    );
    // Six motions: gestures of classes 0..=5 only, of a table of ten: any set of
    // classes loads.
    let lib = random_library(&spec(6, 12), 1);
    assert_eq!(read_library(&write_library(&lib), NAME), Ok(lib.clone()));
    assert_eq!(validate(&lib), Ok(()));
}

#[test]
fn class_tables_of_any_size_round_trip() {
    let mut lib = random_library(&spec(3, 6), 4);
    lib.classes = vec!["sweep".into(), "Zara-walk_2".into(), "x".into()];
    let bytes = write_library(&lib);
    assert_eq!(read_library(&bytes, NAME), Ok(lib.clone()));
    assert_eq!(lib.class_id("Zara-walk_2"), Some(ClassId(1)));
    assert_eq!(lib.class_name(ClassId(2)), "x");
    assert_eq!(lib.kind(ClassId(0)), None);
    let counts = lib.counts();
    assert_eq!(
        counts
            .iter()
            .map(|c| (c.motions, c.gestures))
            .collect::<Vec<_>>(),
        [(1, 2), (1, 2), (1, 2)]
    );
    // One class, one motion, one gesture is a complete library.
    let one = Library {
        classes: vec!["only".into()],
        motions: vec![lib.motions[0].clone()],
        gestures: vec![lib.gestures[0].clone()],
    };
    assert_eq!(read_library(&write_library(&one), NAME), Ok(one));
}

#[test]
fn duplicate_and_bad_class_names_are_located() {
    let mut lib = random_library(&spec(3, 3), 4);
    lib.classes = vec!["sweep".into(), "wave".into(), "sweep".into()];
    let at = class_offset(&lib, 2);
    let e = read_err(&write_library(&lib));
    assert_eq!(
        e.to_string(),
        format!(
            "library.ctgl: offset {}: class 2: class `sweep` is named twice (also class 0)",
            at + 4
        )
    );
    assert_eq!(
        validate(&lib).unwrap_err().to_string(),
        "(in memory): class 2: class `sweep` is named twice (also class 0)"
    );
    lib.classes[2] = "two words".into();
    let e = read_err(&write_library(&lib));
    assert_eq!(e.item, Item::Class(2));
    assert!(
        matches!(
            &e.problem,
            Problem::BadClassName(b) if matches!(**b, ClassNameError::BadCharacter { at: 3, .. })
        ),
        "{e}"
    );
    lib.classes[2] = String::new();
    let e = read_err(&write_library(&lib));
    assert_eq!((e.offset, &e.item), (Some(at), &Item::Class(2)));
    assert!(
        matches!(
            e.problem,
            Problem::BadCount {
                what: "class name byte",
                count: 0,
                ..
            }
        ),
        "{e}"
    );
    // A name that is not UTF-8, at its byte.
    lib.classes[2] = "ab".into();
    let mut bytes = write_library(&lib);
    bytes[at + 5] = 0xff;
    reseal(&mut bytes);
    let e = read_err(&bytes);
    assert_eq!(
        (e.offset, &e.problem),
        (
            Some(at + 5),
            &Problem::NotUtf8 {
                what: "class name",
                at: 1
            }
        )
    );
}

#[test]
fn a_class_with_gestures_but_no_motions_is_named() {
    // Class 2 ("contract") loses its only motion; its gesture still names it.
    let mut lib = random_library(&spec(3, 3), 5);
    lib.motions[2].class = ClassId(1);
    let e = validate(&lib).unwrap_err();
    assert_eq!(
        e.to_string(),
        "(in memory): gesture 2: class `contract` has gestures but no motions (import one with `library import-motion --class contract`)"
    );
    let at = gesture_offset(&lib, 2);
    let e = read_err(&write_library(&lib));
    assert_eq!((e.offset, &e.item), (Some(at), &Item::Gesture(2)));
    assert!(
        matches!(&e.problem, Problem::ClassWithoutMotions { class } if class == "contract"),
        "{e}"
    );
    // A gesture pointing at a motion of another class, while its class has
    // motions, is a mismatch named by both classes.
    let mut lib = random_library(&spec(3, 3), 5);
    lib.gestures[2].motion = 1;
    let e = validate(&lib).unwrap_err().to_string();
    assert!(
        e.ends_with("class `contract` differs from its motion 1's class `twist`"),
        "{e}"
    );
}

#[test]
fn removing_a_class_renumbers_classes_and_motions() {
    let lib = random_library(&spec(10, 30), 6);
    let mut cut = lib.clone();
    cut.remove_class(ClassId(3));
    assert_eq!(cut.classes.len(), 9);
    assert!(!cut.classes.iter().any(|c| c == "expand"));
    assert_eq!(cut.motions.len(), 9);
    assert_eq!(cut.gestures.len(), 27);
    validate(&cut).unwrap();
    // Every kept gesture still names the same motion, by its new index.
    let kept: Vec<&LibraryGesture> = lib
        .gestures
        .iter()
        .filter(|g| g.class != ClassId(3))
        .collect();
    for (old, new) in kept.iter().zip(&cut.gestures) {
        assert_eq!(old.origin, new.origin);
        assert_eq!(
            lib.motions[old.motion as usize].mean,
            cut.motions[new.motion as usize].mean
        );
        assert_eq!(
            lib.class_name(old.class),
            cut.class_name(new.class),
            "{}",
            old.origin
        );
    }
    cut.remove_class(ClassId(100));
    assert_eq!(cut.classes.len(), 9);
}

#[test]
fn version_1_files_read_as_the_ten_classes() {
    let lib = small();
    let old = write_v1(&lib);
    assert_eq!(&old[4..8], &1u32.to_le_bytes());
    let mut expect = lib.clone();
    for g in &mut expect.gestures {
        g.participant.clear();
        g.device.clear();
        g.scale_mm = None;
    }
    let read = read_library(&old, NAME).unwrap();
    assert_eq!(read, expect);
    assert_eq!(read.classes, MotionClass::all_names());
    // Written again, it is version 2 and reads as the same library.
    let new = write_library(&read);
    assert_eq!(&new[4..8], &FORMAT_VERSION.to_le_bytes());
    assert_eq!(read_library(&new, NAME), Ok(expect));
    // A version-1 file's class beyond the ten is named against the ten.
    let mut bad = old.clone();
    let at = 16 + lib.motions.iter().map(motion_bytes).sum::<usize>();
    bad[at..at + 4].copy_from_slice(&10u32.to_le_bytes());
    reseal(&mut bad);
    let e = read_err(&bad);
    assert_eq!(
        (e.offset, e.problem),
        (
            Some(at),
            Problem::BadClass {
                index: 10,
                count: 10
            }
        )
    );
    // The shipped file is written by this build: the newest version.
    assert_eq!(
        &super::super::SHIPPED_BYTES[4..8],
        &FORMAT_VERSION.to_le_bytes()
    );
}

#[test]
fn participant_and_device_round_trip_and_are_capped() {
    let mut lib = small();
    lib.gestures[4].participant = "P07".into();
    lib.gestures[4].device = "Dell Canvas 27 (hidraw)".into();
    assert_eq!(read_library(&write_library(&lib), NAME), Ok(lib.clone()));
    lib.gestures[4].participant = "p".repeat(65);
    let e = read_err(&write_library(&lib));
    assert_eq!(
        e.offset,
        Some(gesture_offset(&lib, 4) + 16),
        "at its length field"
    );
    assert!(
        matches!(
            e.problem,
            Problem::BadCount {
                what: "participant byte",
                count: 65,
                ..
            }
        ),
        "{e}"
    );
    assert!(validate(&lib).is_err());
    lib.gestures[4].participant.clear();
    lib.gestures[4].device = "d".repeat(257);
    let e = read_err(&write_library(&lib));
    assert!(
        matches!(
            e.problem,
            Problem::BadCount {
                what: "device byte",
                count: 257,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn a_flipped_byte_is_a_checksum_error_or_caught_before() {
    let bytes = write_library(&random_library(&spec(10, 10), 9));
    let mut copy = bytes.clone();
    for i in (0..bytes.len()).step_by(97) {
        copy[i] ^= 0x10;
        assert!(read_library(&copy, NAME).is_err(), "flip at {i}");
        copy[i] = bytes[i];
    }
}

#[test]
fn origin_must_be_utf8_and_short() {
    let mut lib = small();
    lib.gestures[0].origin = "é".repeat(600);
    let e = read_err(&write_library(&lib));
    assert!(
        matches!(
            e.problem,
            Problem::BadCount {
                what: "origin byte",
                count: 1200,
                ..
            }
        ),
        "{e}"
    );
    let lib = small();
    let mut bytes = write_library(&lib);
    let g = &lib.gestures[0];
    let at = gesture_offset(&lib, 1) - g.origin.len() - g.participant.len() - g.device.len();
    bytes[at] = 0xff;
    reseal(&mut bytes);
    let e = read_err(&bytes);
    assert_eq!(
        (e.offset, &e.problem),
        (
            Some(at),
            &Problem::NotUtf8 {
                what: "origin",
                at: 0
            }
        )
    );
}

fn any_spec() -> impl Strategy<Value = (RandomLibrarySpec, u64)> {
    (
        0usize..14,
        0usize..20,
        0usize..=15,
        1usize..4,
        1usize..=10,
        any::<u64>(),
    )
        .prop_map(
            |(motions, gestures, components, gmm_components, max_fingers, seed)| {
                (
                    RandomLibrarySpec {
                        motions,
                        gestures,
                        components,
                        gmm_components,
                        max_fingers,
                    },
                    seed,
                )
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn write_then_read_is_the_identity((spec, seed) in any_spec()) {
        let lib = random_library(&spec, seed);
        prop_assert_eq!(validate_with(&lib, LoadPolicy::Partial), Ok(()));
        let bytes = write_library(&lib);
        prop_assert_eq!(read_library_with(&bytes, NAME, LoadPolicy::Partial), Ok(lib.clone()));
        prop_assert_eq!(read_library(&bytes, NAME).is_ok(), validate(&lib).is_ok());
    }

    #[test]
    fn a_corrupt_byte_errors_or_reads_a_valid_library(
        (spec, seed) in any_spec(), at in any::<prop::sample::Index>(), xor in 1u8..=255, resealed in any::<bool>()
    ) {
        let lib = random_library(&spec, seed);
        let mut bytes = write_library(&lib);
        let i = at.index(bytes.len());
        bytes[i] ^= xor;
        if resealed {
            reseal(&mut bytes);
        }
        match read_library_with(&bytes, NAME, LoadPolicy::Partial) {
            Ok(read) => {
                prop_assert!(resealed, "a flipped byte passed the checksum");
                prop_assert_eq!(validate_with(&read, LoadPolicy::Partial), Ok(()));
            }
            Err(e) => prop_assert!(e.to_string().starts_with("library.ctgl: offset "), "{}", e),
        }
    }
}
