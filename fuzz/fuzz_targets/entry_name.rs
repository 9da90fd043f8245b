#![no_main]
//! The entry names clients give instead of paths (`check_entry_name`,
//! `entry_path`) and the capped reader every named file goes through
//! (`read_bytes`, `read_entry_text`). The first byte is the cap (0..=255 bytes),
//! the rest is both a candidate name and a file's content.
//!
//! A name that is accepted names exactly one entry of the directory: no `/`, not
//! `.` or `..` or hidden, at most `MAX_ENTRY_NAME_BYTES`, and the joined path's
//! parent is the directory. The read of a file of `n` bytes with cap `c` returns
//! the bytes when `n <= c` and is refused by size otherwise; an accepted name read
//! as an entry gives the same answer.
use crowdtouch::located::{
    check_entry_name, entry_path, read_bytes, read_entry_text, EntryError, ReadError,
    MAX_ENTRY_NAME_BYTES,
};
use libfuzzer_sys::fuzz_target;
use std::path::{Component, Path};
use std::sync::OnceLock;

fn dir() -> &'static Path {
    static DIR: OnceLock<std::path::PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("ct-fuzz-entry-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&cap, rest)) = data.split_first() else {
        return;
    };
    let cap = u64::from(cap);
    let name = String::from_utf8_lossy(rest);
    let d = dir();
    match check_entry_name(&name) {
        Ok(()) => {
            assert!(!name.is_empty() && name.len() <= MAX_ENTRY_NAME_BYTES);
            assert!(!name.contains('/') && !name.contains('\0') && !name.starts_with('.'));
            let p = entry_path(d, &name).expect("an accepted name joins");
            assert_eq!(p.parent(), Some(d), "{name:?}");
            let comps: Vec<_> = Path::new(&*name).components().collect();
            assert!(matches!(comps.as_slice(), [Component::Normal(_)]), "{name:?}");
        }
        Err(_) => assert!(entry_path(d, &name).is_err()),
    }
    // The capped reader over a file holding `rest`.
    let file = d.join("content");
    std::fs::write(&file, rest).unwrap();
    match read_bytes(&file, cap) {
        Ok(bytes) => {
            assert!(rest.len() as u64 <= cap);
            assert_eq!(bytes, rest);
        }
        Err(ReadError::TooLarge { size, max, .. }) => {
            assert_eq!((size, max), (rest.len() as u64, cap));
            assert!(size > cap);
        }
        Err(e) => panic!("{e}"),
    }
    if check_entry_name(&name).is_ok() && name != "content" {
        // Not created: the entry does not exist.
        match read_entry_text(d, &name, cap, &|| false) {
            Err(EntryError::Read(ReadError::Io { source, .. })) => {
                assert_eq!(source.kind(), std::io::ErrorKind::NotFound)
            }
            other => panic!("{name:?}: {other:?}"),
        }
    }
});
