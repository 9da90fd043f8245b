use super::*;
use crate::gesture::library::{random_library, validate, validate_with, RandomLibrarySpec};
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

/// Offset of gesture `g`'s record in the file of `lib`.
fn gesture_offset(lib: &Library, g: usize) -> usize {
    HEADER_BYTES
        + lib.motions.iter().map(motion_bytes).sum::<usize>()
        + lib.gestures[..g]
            .iter()
            .map(|g| GESTURE_HEAD_BYTES + g.gesture.fingers.len() * FINGER_BYTES + g.origin.len())
            .sum::<usize>()
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
        "library.ctgl: offset 4: header: format version 3; this reader reads versions 1 to 2"
    );
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
    bytes[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
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
    assert_eq!((e.offset, &e.problem), (Some(at), &Problem::BadClass(10)));
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
    assert_eq!(
        e.problem,
        Problem::Empty {
            motions: 0,
            gestures: 0
        }
    );
    assert_eq!(
        read_library_with(&write_library(&empty), NAME, LoadPolicy::Partial),
        Ok(empty.clone())
    );
    // Six motions: classes 0..=5 only.
    let lib = random_library(&spec(6, 12), 1);
    let e = read_err(&write_library(&lib));
    assert_eq!(
        e.to_string(),
        format!(
            "library.ctgl: offset {}: library: no gesture for classes: split_then_translate, translate_then_join, twist_while_expanding, twist_while_contracting",
            write_library(&lib).len() - 4
        )
    );
    assert!(validate(&lib).is_err());
    assert_eq!(validate_with(&lib, LoadPolicy::Partial), Ok(()));
    assert_eq!(
        read_library_with(&write_library(&lib), NAME, LoadPolicy::Partial),
        Ok(lib)
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
    let at = gesture_offset(&lib, 1) - lib.gestures[0].origin.len();
    bytes[at] = 0xff;
    reseal(&mut bytes);
    let e = read_err(&bytes);
    assert_eq!(
        (e.offset, &e.problem),
        (Some(at), &Problem::OriginNotUtf8(0))
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
