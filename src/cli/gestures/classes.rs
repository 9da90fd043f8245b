//! A gesture class named on the command line.

use anyhow::{anyhow, Result};
use crowdtouch::gesture::library::{ClassId, Library};

/// The id of the class `name` of `lib`, or an error listing its classes.
pub(super) fn class_of(lib: &Library, name: &str) -> Result<ClassId> {
    lib.class_id(name).ok_or_else(|| {
        anyhow!(
            "the library has no class `{}`; its classes are: {}",
            crowdtouch::located::Escaped(name),
            if lib.classes.is_empty() {
                "(none)".to_string()
            } else {
                lib.classes.join(", ")
            }
        )
    })
}
