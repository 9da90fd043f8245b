#![no_main]
//! Arbitrary library files: `read_library_with` answers with a library or an error
//! naming the file and offset, never a panic. The first input byte is a control
//! byte, the rest the file: when the control byte is odd the file's trailing
//! checksum is rewritten first, so mutations reach the checks behind it. An
//! accepted library passes `validate_with`; a file of the current version writes
//! back to the same bytes, an older one (migrated on read) to a current file that
//! reads as the same library.
use crowdtouch::gesture::library::{
    read_library_with, reseal, validate_with, write_library, LoadPolicy, FORMAT_VERSION,
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
            let written = write_library(&lib);
            if bytes[4..8] == FORMAT_VERSION.to_le_bytes() {
                assert_eq!(written, bytes, "an accepted file is written back as read");
            } else {
                let again = read_library_with(&written, "fuzz.ctgl", LoadPolicy::Partial)
                    .expect("a migrated library reads back");
                assert_eq!(again, lib, "a migrated library is written as read");
            }
        }
        Err(e) => assert!(e.to_string().starts_with("fuzz.ctgl: offset ")),
    }
});
