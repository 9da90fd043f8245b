#![no_main]
//! Arbitrary library files: `read_library_with` answers with a library or an error
//! naming the file and offset, never a panic. The first input byte is a control
//! byte, the rest the file: when the control byte is odd the file's trailing
//! checksum is rewritten first, so mutations reach the checks behind it. An accepted library passes `validate_with` and writes back to the same bytes.
use crowdtouch::gesture::library::{
    read_library_with, reseal, validate_with, write_library, LoadPolicy,
};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&control, file)) = data.split_first() else {
        return;
    };
    let mut bytes = file.to_vec();
    if control & 1 == 1 {
        reseal(&mut bytes);
    }
    match read_library_with(&bytes, "fuzz.ctgl", LoadPolicy::Partial) {
        Ok(lib) => {
            validate_with(&lib, LoadPolicy::Partial).expect("an accepted library is valid");
            assert_eq!(write_library(&lib), bytes, "an accepted file is written back as read");
        }
        Err(e) => assert!(e.to_string().starts_with("fuzz.ctgl: offset ")),
    }
});
