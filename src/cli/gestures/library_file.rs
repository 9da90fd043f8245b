//! The library files the `library` commands read and write: a file or the shipped
//! library, complete or partial, and a library checked and written back.

use anyhow::{anyhow, Context, Result};
use crowdtouch::gesture::library::{
    read_library_with, shipped, validate_with, write_library, Library, LoadPolicy,
    MAX_LIBRARY_BYTES,
};
use std::path::Path;

/// Checks `lib` under [`LoadPolicy::Partial`] and writes it to `out`, read back
/// first from the bytes to be written.
pub fn save(lib: &Library, out: &Path) -> Result<usize> {
    validate_with(lib, LoadPolicy::Partial).map_err(|mut e| {
        e.file = out.display().to_string();
        e
    })?;
    let bytes = write_library(lib);
    read_library_with(&bytes, &out.display().to_string(), LoadPolicy::Partial)?;
    std::fs::write(out, &bytes).with_context(|| format!("{}: cannot write", out.display()))?;
    Ok(bytes.len())
}

/// A library file, or the shipped library.
pub fn load(path: Option<&Path>) -> Result<Library> {
    load_with(path, LoadPolicy::Complete)
}

pub fn load_with(path: Option<&Path>, policy: LoadPolicy) -> Result<Library> {
    match path {
        None => Ok(shipped()?),
        Some(p) => {
            let bytes = crowdtouch::located::read_bytes(p, MAX_LIBRARY_BYTES as u64)
                .map_err(|e| anyhow!("cannot read library: {e}"))?;
            Ok(read_library_with(&bytes, &p.display().to_string(), policy)?)
        }
    }
}
