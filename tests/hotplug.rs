//! The inotify watcher and `wait_ready` on temporary directory trees.
//!
//! Tests run as any user, including root (which may open any file), so the
//! permission tests pass an open check that behaves like an unprivileged user: a
//! node is readable once its mode grants read to group or others.

use crowdtouch::input::hotplug::{HotplugEvent, ReadyError, Watcher};
use crowdtouch::input::udev::UdevDb;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::thread;
use std::time::{Duration, Instant};

/// How long to wait for an event that must come.
const EVENT_WAIT: Duration = Duration::from_secs(5);
/// How long the tree must stay quiet to count as "no more events".
const QUIET: Duration = Duration::from_millis(150);
/// Delay between the steps another thread performs.
const STEP: Duration = Duration::from_millis(60);

fn tree(with_udev: bool) -> tempfile::TempDir {
    let t = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(t.path().join("dev/input")).unwrap();
    std::fs::create_dir_all(t.path().join("sys/class/input")).unwrap();
    if with_udev {
        std::fs::create_dir_all(t.path().join("run/udev/data")).unwrap();
    }
    t
}

/// Events until the tree has been quiet for [`QUIET`], consecutive duplicates merged.
fn collect(w: &mut Watcher) -> Vec<HotplugEvent> {
    let mut out: Vec<HotplugEvent> = Vec::new();
    while let Some(e) = w.next(QUIET).unwrap() {
        if out.last() != Some(&e) {
            out.push(e);
        }
    }
    out
}

/// Simulates an unprivileged user: readable when group or others may read.
fn user_open(node: &Path) -> std::io::Result<()> {
    let mode = std::fs::metadata(node)?.permissions().mode();
    if mode & 0o044 != 0 {
        Ok(())
    } else {
        Err(std::io::Error::from_raw_os_error(nix::libc::EACCES))
    }
}

fn chmod(path: &Path, mode: u32) {
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode)).unwrap();
}

/// The sysfs `dev` file udev's record name comes from.
fn sysfs_dev(root: &Path, event_n: u32, minor: u32) {
    let dir = root.join(format!("sys/class/input/event{event_n}"));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("dev"), format!("13:{minor}\n")).unwrap();
}

#[test]
fn create_chmod_delete_are_reported_for_touch_nodes_only() {
    let t = tree(true);
    let root = t.path();
    let mut w = Watcher::new(root).unwrap();
    let ev = root.join("dev/input/event3");
    let hr = root.join("dev/hidraw1");
    std::fs::write(&ev, "").unwrap();
    std::fs::write(root.join("dev/input/mouse0"), "").unwrap();
    std::fs::write(root.join("dev/tty5"), "").unwrap();
    chmod(&ev, 0o660);
    std::fs::write(&hr, "").unwrap();
    std::fs::remove_file(&ev).unwrap();
    // udev writes its record to a temporary name and renames it into place.
    let data = root.join("run/udev/data");
    std::fs::write(data.join(".#c13:67XYZ"), "E:ID_PATH=x\n").unwrap();
    std::fs::rename(data.join(".#c13:67XYZ"), data.join("c13:67")).unwrap();
    std::fs::write(data.join("n3"), "").unwrap();
    assert_eq!(
        collect(&mut w),
        vec![
            HotplugEvent::Added(ev.clone()),
            HotplugEvent::Changed(ev.clone()),
            HotplugEvent::Added(hr.clone()),
            HotplugEvent::Removed(ev),
            HotplugEvent::UdevProcessed(data.join("c13:67")),
        ]
    );
    // A record written in place is reported too (created, then closed).
    std::fs::write(data.join("c244:1"), "E:ID_PATH=y\n").unwrap();
    assert_eq!(
        collect(&mut w),
        vec![HotplugEvent::UdevProcessed(data.join("c244:1"))]
    );
    // Moving a node away is a removal.
    std::fs::rename(&hr, root.join("hidraw1.old")).unwrap();
    assert_eq!(collect(&mut w), vec![HotplugEvent::Removed(hr)]);
}

#[test]
fn next_blocks_until_the_timeout_when_nothing_happens() {
    let t = tree(false);
    let mut w = Watcher::new(t.path()).unwrap();
    let start = Instant::now();
    assert_eq!(w.next(Duration::from_millis(200)).unwrap(), None);
    let took = start.elapsed();
    assert!(took >= Duration::from_millis(200), "{took:?}");
    assert!(took < Duration::from_secs(3), "{took:?}");
}

#[test]
fn next_wakes_up_for_an_event_from_another_thread() {
    let t = tree(false);
    let root = t.path().to_path_buf();
    let mut w = Watcher::new(&root).unwrap();
    let node = root.join("dev/input/event2");
    let n2 = node.clone();
    let h = thread::spawn(move || {
        thread::sleep(STEP);
        std::fs::write(n2, "").unwrap();
    });
    let start = Instant::now();
    assert_eq!(w.next(EVENT_WAIT).unwrap(), Some(HotplugEvent::Added(node)));
    assert!(start.elapsed() < EVENT_WAIT);
    h.join().unwrap();
}

#[test]
fn input_directory_created_later_is_watched() {
    let t = tempfile::tempdir().unwrap();
    let root = t.path();
    std::fs::create_dir_all(root.join("dev")).unwrap();
    let mut w = Watcher::new(root).unwrap();
    std::fs::create_dir(root.join("dev/input")).unwrap();
    let ev0 = root.join("dev/input/event0");
    std::fs::write(&ev0, "").unwrap();
    let first = w.next(EVENT_WAIT).unwrap();
    assert_eq!(first, Some(HotplugEvent::Added(ev0.clone())));
    // The node may be announced twice (seen by the directory scan and by the new
    // watch); nothing else comes.
    let rest = collect(&mut w);
    assert!(
        rest.iter().all(|e| *e == HotplugEvent::Added(ev0.clone())),
        "{rest:?}"
    );
    let ev1 = root.join("dev/input/event1");
    std::fs::write(&ev1, "").unwrap();
    assert_eq!(collect(&mut w), vec![HotplugEvent::Added(ev1)]);
}

#[test]
fn missing_dev_directory_is_an_error_naming_it() {
    let t = tempfile::tempdir().unwrap();
    let e = Watcher::new(t.path()).unwrap_err();
    assert!(
        e.to_string()
            .contains(&t.path().join("dev").display().to_string()),
        "{e}"
    );
}

#[test]
fn wait_ready_follows_create_udev_record_and_chmod() {
    let t = tree(true);
    let root = t.path().to_path_buf();
    let udev = UdevDb::new(&root);
    let mut w = Watcher::new(&root).unwrap();
    let node = root.join("dev/input/event6");
    let record = udev.record_path(13, 70);
    let (n2, r2, root2) = (node.clone(), record.clone(), root.clone());
    let helper = thread::spawn(move || {
        // The kernel creates the node (root only)...
        thread::sleep(STEP);
        sysfs_dev(&root2, 6, 70);
        std::fs::write(&n2, "").unwrap();
        chmod(&n2, 0o600);
        // ...udev runs its rules and writes the record...
        thread::sleep(STEP);
        std::fs::write(&r2, "E:ID_PATH=pci-0000:00:14.0-usb-0:1:1.0\n").unwrap();
        // ...and then the rule's group and mode land.
        thread::sleep(STEP);
        chmod(&n2, 0o660);
    });
    let start = Instant::now();
    let mut opens = 0;
    w.wait_ready_with(&node, &udev, EVENT_WAIT, |p| {
        opens += 1;
        // Never asked to open before udev is done with the node.
        assert!(record.is_file(), "open tried before the udev record");
        user_open(p)
    })
    .unwrap();
    assert!(start.elapsed() < EVENT_WAIT);
    assert_eq!(
        std::fs::metadata(&node).unwrap().permissions().mode() & 0o777,
        0o660
    );
    assert!(opens >= 1);
    helper.join().unwrap();
}

#[test]
fn wait_ready_with_the_real_open_needs_the_udev_record() {
    let t = tree(true);
    let root = t.path().to_path_buf();
    let udev = UdevDb::new(&root);
    let mut w = Watcher::new(&root).unwrap();
    let node = root.join("dev/input/event8");
    let record = udev.record_path(13, 72);
    let (n2, r2, root2) = (node.clone(), record.clone(), root.clone());
    let helper = thread::spawn(move || {
        thread::sleep(STEP);
        sysfs_dev(&root2, 8, 72);
        std::fs::write(&n2, "").unwrap();
        chmod(&n2, 0o644);
        thread::sleep(STEP);
        std::fs::write(&r2, "E:ID_INPUT=1\n").unwrap();
    });
    w.wait_ready(&node, &udev, EVENT_WAIT).unwrap();
    assert!(record.is_file(), "ready before udev processed the node");
    helper.join().unwrap();
}

#[test]
fn without_udev_ready_means_present_and_openable() {
    let t = tree(false);
    let root = t.path().to_path_buf();
    let udev = UdevDb::new(&root);
    assert!(!udev.present());
    let mut w = Watcher::new(&root).unwrap();
    let node = root.join("dev/hidraw3");
    let n2 = node.clone();
    let helper = thread::spawn(move || {
        thread::sleep(STEP);
        std::fs::write(&n2, "").unwrap();
        chmod(&n2, 0o666);
    });
    w.wait_ready(&node, &udev, EVENT_WAIT).unwrap();
    helper.join().unwrap();
}

#[test]
fn permission_that_never_comes_times_out_clearly() {
    let t = tree(true);
    let root = t.path();
    let udev = UdevDb::new(root);
    sysfs_dev(root, 4, 68);
    let node = root.join("dev/input/event4");
    std::fs::write(&node, "").unwrap();
    chmod(&node, 0o600);
    std::fs::write(udev.record_path(13, 68), "E:ID_INPUT=1\n").unwrap();
    let mut w = Watcher::new(root).unwrap();
    let timeout = Duration::from_millis(300);
    let start = Instant::now();
    let e = w
        .wait_ready_with(&node, &udev, timeout, user_open)
        .unwrap_err();
    assert!(start.elapsed() >= timeout);
    assert!(matches!(e, ReadyError::PermissionDenied { .. }), "{e:?}");
    let msg = e.to_string();
    assert!(msg.contains(&node.display().to_string()), "{msg}");
    assert!(
        msg.contains("permission denied") && msg.contains("udev rule"),
        "{msg}"
    );
}

#[test]
fn unrelated_changes_do_not_end_the_wait_early() {
    let t = tree(true);
    let root = t.path().to_path_buf();
    let udev = UdevDb::new(&root);
    sysfs_dev(&root, 4, 68);
    let node = root.join("dev/input/event4");
    std::fs::write(&node, "").unwrap();
    chmod(&node, 0o600);
    std::fs::write(udev.record_path(13, 68), "E:ID_INPUT=1\n").unwrap();
    let mut w = Watcher::new(&root).unwrap();
    let (n2, other) = (node.clone(), root.join("dev/input/event9"));
    let helper = thread::spawn(move || {
        // An unrelated node comes and goes, then udev fixes the mode of ours.
        thread::sleep(STEP);
        std::fs::write(&other, "").unwrap();
        std::fs::remove_file(&other).unwrap();
        thread::sleep(STEP);
        chmod(&n2, 0o640);
    });
    w.wait_ready_with(&node, &udev, EVENT_WAIT, user_open)
        .unwrap();
    assert_eq!(
        std::fs::metadata(&node).unwrap().permissions().mode() & 0o777,
        0o640
    );
    helper.join().unwrap();
}

#[test]
fn missing_node_and_missing_record_time_out_with_their_own_errors() {
    let t = tree(true);
    let root = t.path();
    let udev = UdevDb::new(root);
    let mut w = Watcher::new(root).unwrap();
    let timeout = Duration::from_millis(150);

    let ghost = root.join("dev/input/event11");
    let e = w.wait_ready(&ghost, &udev, timeout).unwrap_err();
    assert!(matches!(e, ReadyError::Missing { .. }), "{e:?}");
    assert!(e.to_string().contains("did not appear"), "{e}");

    sysfs_dev(root, 12, 76);
    let node = root.join("dev/input/event12");
    std::fs::write(&node, "").unwrap();
    let e = w.wait_ready(&node, &udev, timeout).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, ReadyError::NotProcessed { .. }), "{e:?}");
    assert!(msg.contains("c13:76") && msg.contains("udev"), "{msg}");
}

#[test]
fn other_open_failures_are_reported_at_once() {
    let t = tree(false);
    let root = t.path();
    let node: PathBuf = root.join("dev/input/event1");
    std::fs::write(&node, "").unwrap();
    let mut w = Watcher::new(root).unwrap();
    let start = Instant::now();
    let e = w
        .wait_ready_with(&node, &UdevDb::new(root), EVENT_WAIT, |_| {
            Err(std::io::Error::from_raw_os_error(nix::libc::ENODEV))
        })
        .unwrap_err();
    assert!(start.elapsed() < EVENT_WAIT);
    assert!(e.to_string().contains("unplugged"), "{e}");
}
