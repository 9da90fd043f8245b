//! The one reader of named files (`located::read`, issue 27 findings 2 and 3):
//! a FIFO without a writer, `/dev/zero`, a directory, a 10 GB sparse file, a file
//! over the cap, one that reads longer than it reports, a read stopped between
//! chunks; and the entry names clients give instead of paths (`/`, `..`, NUL,
//! absolute paths, a symbolic link out of the directory).

use crowdtouch::located::{
    check_entry_name, entry_path, read_bytes, read_entry_text, read_text, read_text_stoppable,
    EntryError, NameError, ReadError, MAX_ENTRY_NAME_BYTES, READ_CHUNK_BYTES,
};
use std::fs::File;
use std::path::Path;
use std::time::{Duration, Instant};

fn never() -> bool {
    false
}

/// A FIFO with no writer: the open does not block and the FIFO is refused, well
/// within a second.
#[test]
fn a_fifo_without_a_writer_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo");
    let status = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(status.success());
    let (tx, rx) = std::sync::mpsc::channel();
    let p = fifo.clone();
    std::thread::spawn(move || {
        let _ = tx.send(read_text(&p, 1 << 20).map(|_| ()));
    });
    let got = rx
        .recv_timeout(Duration::from_secs(1))
        .expect("the read of a FIFO returned within 1 s");
    let e = got.unwrap_err();
    assert!(
        matches!(
            e,
            ReadError::NotRegular {
                kind: "is a FIFO",
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(
        e.to_string(),
        format!("{}: is a FIFO, not a regular file", fifo.display())
    );
}

/// `/dev/zero` is a character device: refused before a byte is read.
#[test]
fn dev_zero_is_refused_as_a_character_device() {
    let t = Instant::now();
    let e = read_bytes(Path::new("/dev/zero"), 1 << 20).unwrap_err();
    assert!(
        matches!(
            e,
            ReadError::NotRegular {
                kind: "is a character device",
                ..
            }
        ),
        "{e}"
    );
    assert!(t.elapsed() < Duration::from_secs(1));
    let e = read_text(Path::new("/dev/zero"), 1 << 20).unwrap_err();
    assert_eq!(
        e.to_string(),
        "/dev/zero: is a character device, not a regular file"
    );
}

#[test]
fn a_directory_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let e = read_text(dir.path(), 1 << 20).unwrap_err();
    assert!(
        matches!(
            e,
            ReadError::NotRegular {
                kind: "is a directory",
                ..
            }
        ),
        "{e}"
    );
}

/// A 10 GB sparse file is refused by the size it reports, without reading.
#[test]
fn a_10_gb_sparse_file_is_refused_by_its_size_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("big.jsonl");
    File::create(&p).unwrap().set_len(10_000_000_000).unwrap();
    let t = Instant::now();
    let e = read_text(&p, 256 << 20).unwrap_err();
    assert!(t.elapsed() < Duration::from_secs(1));
    assert!(
        matches!(
            e,
            ReadError::TooLarge {
                size: 10_000_000_000,
                max: 268_435_456,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn a_file_over_the_cap_is_refused_and_one_at_the_cap_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("f");
    std::fs::write(&p, vec![b'a'; 101]).unwrap();
    let e = read_text(&p, 100).unwrap_err();
    assert!(
        matches!(
            e,
            ReadError::TooLarge {
                size: 101,
                max: 100,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(read_text(&p, 101).unwrap().len(), 101);
    // Over several chunks.
    let big = vec![b'b'; 2 * READ_CHUNK_BYTES + 17];
    std::fs::write(&p, &big).unwrap();
    assert_eq!(read_bytes(&p, big.len() as u64).unwrap(), big);
}

/// A file whose reported size is small but that yields more (here a /proc file
/// reporting 0 bytes) is read through the cap: at most `cap + 1` bytes.
#[test]
fn a_file_that_reads_longer_than_it_reports_is_cut_at_the_cap() {
    let p = Path::new("/proc/self/maps");
    assert_eq!(std::fs::metadata(p).unwrap().len(), 0);
    let e = read_bytes(p, 8).unwrap_err();
    assert!(matches!(e, ReadError::GrewPastCap { max: 8, .. }), "{e}");
}

#[test]
fn text_that_is_not_utf8_is_named_with_its_offset() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("f");
    std::fs::write(&p, b"ab\xffcd").unwrap();
    let e = read_text(&p, 100).unwrap_err();
    assert!(matches!(e, ReadError::NotUtf8 { offset: 2, .. }), "{e}");
}

/// The stop check is polled between chunks: a read asked to stop ends with
/// [`ReadError::Stopped`].
#[test]
fn a_stoppable_read_stops_between_chunks() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("f");
    std::fs::write(&p, vec![b'c'; 3 * READ_CHUNK_BYTES]).unwrap();
    let polls = std::cell::Cell::new(0);
    let stop = || {
        polls.set(polls.get() + 1);
        polls.get() > 2
    };
    let e = read_text_stoppable(&p, 1 << 30, &stop).unwrap_err();
    assert!(matches!(e, ReadError::Stopped { .. }), "{e}");
    assert_eq!(polls.get(), 3);
    assert_eq!(
        read_text_stoppable(&p, 1 << 30, &never).unwrap().len(),
        3 * READ_CHUNK_BYTES
    );
}

#[test]
fn names_with_slashes_dots_nul_or_odd_characters_are_refused() {
    assert_eq!(check_entry_name(""), Err(NameError::Empty));
    assert_eq!(
        check_entry_name("/etc/shadow"),
        Err(NameError::Slash { at: 0 })
    );
    assert_eq!(
        check_entry_name("../x.jsonl"),
        Err(NameError::Slash { at: 2 })
    );
    assert_eq!(check_entry_name("a/b"), Err(NameError::Slash { at: 1 }));
    assert_eq!(check_entry_name(".."), Err(NameError::Dot));
    assert_eq!(check_entry_name("."), Err(NameError::Dot));
    assert_eq!(check_entry_name(".hidden"), Err(NameError::Dot));
    assert_eq!(
        check_entry_name("a\0b"),
        Err(NameError::BadChar {
            ch: "'\\0'".into(),
            at: 1
        })
    );
    assert!(matches!(
        check_entry_name("a\u{1b}[2J"),
        Err(NameError::BadChar { at: 1, .. })
    ));
    assert!(matches!(
        check_entry_name("é"),
        Err(NameError::BadChar { at: 0, .. })
    ));
    assert!(matches!(
        check_entry_name("a b"),
        Err(NameError::BadChar { at: 1, .. })
    ));
    let long = "a".repeat(MAX_ENTRY_NAME_BYTES + 1);
    assert_eq!(
        check_entry_name(&long),
        Err(NameError::TooLong {
            len: MAX_ENTRY_NAME_BYTES + 1
        })
    );
    for ok in [
        "group.jsonl",
        "a",
        "Run_2-b.csv",
        "x..y",
        &"a".repeat(MAX_ENTRY_NAME_BYTES),
    ] {
        assert_eq!(check_entry_name(ok), Ok(()), "{ok}");
    }
    assert!(entry_path(Path::new("/d"), "..").is_err());
    assert_eq!(
        entry_path(Path::new("/d"), "g.csv").unwrap(),
        Path::new("/d/g.csv")
    );
}

/// An entry that is a symbolic link (here to a file outside the directory) is
/// refused; the file it points to is not read.
#[test]
fn an_entry_that_is_a_symlink_out_of_the_directory_is_refused() {
    let outside = tempfile::tempdir().unwrap();
    let secret = outside.path().join("secret");
    std::fs::write(&secret, "root:*:20228:0:99999:7:::\n").unwrap();
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(&secret, dir.path().join("link.csv")).unwrap();
    let e = read_entry_text(dir.path(), "link.csv", 1 << 20, &never).unwrap_err();
    assert!(
        matches!(
            e,
            EntryError::Read(ReadError::NotRegular {
                kind: "is a symbolic link",
                ..
            })
        ),
        "{e}"
    );
    assert!(!e.to_string().contains("root"), "{e}");
    // A regular entry is read; a path is not a name.
    std::fs::write(dir.path().join("ok.csv"), "t,id,x,y\n").unwrap();
    assert_eq!(
        read_entry_text(dir.path(), "ok.csv", 100, &never).unwrap(),
        "t,id,x,y\n"
    );
    let abs = secret.display().to_string();
    assert!(matches!(
        read_entry_text(dir.path(), &abs, 100, &never),
        Err(EntryError::Name(NameError::Slash { at: 0 }))
    ));
}
