//! The udev database, read directly (no libudev).
//!
//! When udev (systemd-udevd, eudev) has processed a device it writes a record to
//! `/run/udev/data/c<major>:<minor>` for character devices: one fact per line,
//! `E:KEY=VALUE` for properties (`ID_PATH`, `LIBINPUT_CALIBRATION_MATRIX`, ...),
//! `S:` device links, `G:`/`Q:` tags, `I:` the initialisation time. The record's
//! existence is also the signal that udev is done with the node (rules have run,
//! group and mode are set), which [`crate::input::hotplug`] waits for.
//!
//! Every path is taken relative to a root directory (`/` normally) so tests run on a
//! fake tree.

use crate::input::calibrate::{CalibrationError, Matrix};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Where udev keeps its database, relative to the root.
pub const DATA_DIR: &str = "run/udev/data";
/// udev's control socket, relative to the root; present while udevd runs.
pub const CONTROL: &str = "run/udev/control";

/// Read access to udev's database under a root directory.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UdevDb {
    root: PathBuf,
}

impl Default for UdevDb {
    fn default() -> Self {
        UdevDb::system()
    }
}

impl UdevDb {
    /// The database of the running system (root `/`).
    pub fn system() -> UdevDb {
        UdevDb::new("/")
    }

    /// The database under `root` (tests use a temporary directory).
    pub fn new(root: impl Into<PathBuf>) -> UdevDb {
        UdevDb { root: root.into() }
    }

    /// The root directory.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The directory holding the records (`ROOT/run/udev/data`).
    pub fn data_dir(&self) -> PathBuf {
        self.root.join(DATA_DIR)
    }

    /// The record file of a character device (`ROOT/run/udev/data/c<major>:<minor>`).
    pub fn record_path(&self, major: u32, minor: u32) -> PathBuf {
        self.data_dir().join(format!("c{major}:{minor}"))
    }

    /// Whether udev runs on this system (`/run/udev/control` or `/run/udev/data`
    /// exists). Without udev, nodes are never "processed" and nobody waits for it.
    pub fn present(&self) -> bool {
        self.root.join(CONTROL).exists() || self.data_dir().is_dir()
    }

    /// The `E:` properties of a device's record; `None` when there is no readable
    /// record.
    pub fn properties(&self, major: u32, minor: u32) -> Option<BTreeMap<String, String>> {
        let bytes = std::fs::read(self.record_path(major, minor)).ok()?;
        Some(parse_record(&String::from_utf8_lossy(&bytes)))
    }

    /// Whether udev has processed the device: its record exists, or udev is not
    /// present at all (then every node counts as processed).
    pub fn processed(&self, major: u32, minor: u32) -> bool {
        !self.present() || self.record_path(major, minor).is_file()
    }

    /// The device number of a node under this root; see [`device_number`].
    pub fn device_number(&self, node: &Path) -> Option<(u32, u32)> {
        device_number(&self.root, node)
    }
}

/// The `E:KEY=VALUE` properties of a udev database record's text. Other lines
/// (`S:`, `G:`, `I:`, ...) and malformed lines are skipped.
pub fn parse_record(text: &str) -> BTreeMap<String, String> {
    text.lines()
        .filter_map(|line| line.strip_prefix("E:"))
        .filter_map(|kv| kv.split_once('='))
        .filter(|(k, _)| !k.is_empty())
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

/// Parses `LIBINPUT_CALIBRATION_MATRIX` (`"a b c d e f"`, six finite numbers
/// separated by whitespace) into a row-major matrix.
///
/// # Errors
/// [`CalibrationError::MatrixLength`] when there are not six values,
/// [`CalibrationError::MatrixNotANumber`] / [`CalibrationError::MatrixNotFinite`]
/// naming the bad value.
///
/// ```
/// use crowdtouch::input::udev::parse_calibration_matrix;
/// assert_eq!(parse_calibration_matrix("0 -1 1 1 0 0").unwrap(), [0.0, -1.0, 1.0, 1.0, 0.0, 0.0]);
/// assert!(parse_calibration_matrix("1 0 0 0 1").is_err());
/// ```
pub fn parse_calibration_matrix(s: &str) -> Result<Matrix, CalibrationError> {
    let words: Vec<&str> = s.split_whitespace().collect();
    if words.len() != 6 {
        return Err(CalibrationError::MatrixLength { found: words.len() });
    }
    let mut m = [0.0; 6];
    for (index, (slot, word)) in m.iter_mut().zip(&words).enumerate() {
        let v: f64 = word
            .parse()
            .map_err(|_| CalibrationError::MatrixNotANumber {
                index,
                text: (*word).to_string(),
            })?;
        if !v.is_finite() {
            return Err(CalibrationError::MatrixNotFinite { index });
        }
        *slot = v;
    }
    Ok(m)
}

/// Parses a sysfs `dev` file (`"13:69\n"`) into `(major, minor)`.
pub fn parse_dev(text: &str) -> Option<(u32, u32)> {
    let (major, minor) = text.trim().split_once(':')?;
    Some((major.parse().ok()?, minor.parse().ok()?))
}

/// The sysfs class directory of a node's name: `eventN` → `ROOT/sys/class/input/eventN`,
/// `hidrawN` → `ROOT/sys/class/hidraw/hidrawN`; `None` for other names.
pub fn sysfs_class_dir(root: &Path, node: &Path) -> Option<PathBuf> {
    let name = node.file_name()?.to_str()?;
    let class = if name.starts_with("event") {
        "input"
    } else if name.starts_with("hidraw") {
        "hidraw"
    } else {
        return None;
    };
    Some(root.join("sys/class").join(class).join(name))
}

/// The `(major, minor)` device number of a node under `root`.
///
/// A character device node answers by `stat` (its `st_rdev`); anything else (a node
/// that is not there yet, or the plain files of a test tree) by the sysfs `dev`
/// file of its class directory, which is what udev itself uses.
pub fn device_number(root: &Path, node: &Path) -> Option<(u32, u32)> {
    use nix::sys::stat::{major, minor, stat, SFlag};
    if let Ok(st) = stat(node) {
        if SFlag::from_bits_truncate(st.st_mode).contains(SFlag::S_IFCHR) {
            return Some((major(st.st_rdev) as u32, minor(st.st_rdev) as u32));
        }
    }
    let dev = sysfs_class_dir(root, node)?.join("dev");
    parse_dev(&std::fs::read_to_string(dev).ok()?)
}

#[cfg(test)]
mod tests {
    use super::*;

    const RECORD: &str = "S:input/by-path/pci-0000:00:14.0-usb-0:1:1.0-event\n\
        I:4243567\n\
        E:ID_INPUT=1\n\
        E:ID_INPUT_TOUCHSCREEN=1\n\
        E:ID_PATH=pci-0000:00:14.0-usb-0:1:1.0\n\
        E:LIBINPUT_CALIBRATION_MATRIX=0 -1 1 1 0 0\n\
        E:EMPTY=\n\
        E:=novalue\n\
        garbage\n\
        G:seat\n";

    #[test]
    fn record_properties_are_the_e_lines() {
        let p = parse_record(RECORD);
        assert_eq!(p["ID_PATH"], "pci-0000:00:14.0-usb-0:1:1.0");
        assert_eq!(p["LIBINPUT_CALIBRATION_MATRIX"], "0 -1 1 1 0 0");
        assert_eq!(p["EMPTY"], "");
        assert_eq!(p.len(), 5);
    }

    #[test]
    fn calibration_matrix_parses_and_errors_say_why() {
        assert_eq!(
            parse_calibration_matrix("  1.5 0 -0.25\t0 1e0 0 ").unwrap(),
            [1.5, 0.0, -0.25, 0.0, 1.0, 0.0]
        );
        let e = parse_calibration_matrix("1 0 0 0 1").unwrap_err();
        assert_eq!(e, CalibrationError::MatrixLength { found: 5 });
        assert!(e.to_string().contains("6 numbers"));
        let e = parse_calibration_matrix("1 0 x 0 1 0").unwrap_err();
        assert!(e.to_string().contains("value 2 (\"x\")"), "{e}");
        let e = parse_calibration_matrix("1 0 0 0 1 inf").unwrap_err();
        assert_eq!(e, CalibrationError::MatrixNotFinite { index: 5 });
        assert!(parse_calibration_matrix("1 0 0 0 1 NaN").is_err());
        assert!(parse_calibration_matrix("").is_err());
    }

    #[test]
    fn dev_files_parse() {
        assert_eq!(parse_dev("13:69\n"), Some((13, 69)));
        assert_eq!(parse_dev("244:0"), Some((244, 0)));
        assert_eq!(parse_dev("13"), None);
        assert_eq!(parse_dev("a:b"), None);
    }

    #[test]
    fn database_under_a_root() {
        let dir = tempfile::tempdir().unwrap();
        let db = UdevDb::new(dir.path());
        assert!(!db.present());
        // Without udev every node counts as processed and has no properties.
        assert!(db.processed(13, 69));
        assert!(db.properties(13, 69).is_none());
        std::fs::create_dir_all(db.data_dir()).unwrap();
        assert!(db.present());
        assert!(!db.processed(13, 69));
        std::fs::write(db.record_path(13, 69), RECORD).unwrap();
        assert!(db.processed(13, 69));
        assert_eq!(db.properties(13, 69).unwrap()["ID_INPUT_TOUCHSCREEN"], "1");
        assert_eq!(
            db.record_path(13, 69),
            dir.path().join("run/udev/data/c13:69")
        );
    }

    #[test]
    fn device_number_of_plain_files_comes_from_sysfs() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        let node = root.join("dev/input/event5");
        assert_eq!(device_number(root, &node), None);
        std::fs::create_dir_all(root.join("sys/class/input/event5")).unwrap();
        std::fs::write(root.join("sys/class/input/event5/dev"), "13:69\n").unwrap();
        assert_eq!(device_number(root, &node), Some((13, 69)));
        std::fs::create_dir_all(root.join("sys/class/hidraw/hidraw2")).unwrap();
        std::fs::write(root.join("sys/class/hidraw/hidraw2/dev"), "244:2\n").unwrap();
        assert_eq!(
            UdevDb::new(root).device_number(&root.join("dev/hidraw2")),
            Some((244, 2))
        );
        assert_eq!(device_number(root, &root.join("dev/tty0")), None);
        // A real character device answers by stat.
        if let Some((maj, min)) = device_number(Path::new("/"), Path::new("/dev/null")) {
            assert_eq!((maj, min), (1, 3));
        }
    }
}
