//! LinuxCNC's parameter file (`[RS274NGC]PARAMETER_FILE`, the machine configuration's
//! `parameter_file`) for the commands that interpret a program: read before the program
//! runs, the persistent parameters written back when it has run to its end, as LinuxCNC's
//! interpreter keeps them from one program to the next (G10 L2 offsets, the coordinate
//! system in use #5220, G28/G30 positions, G92).
//!
//! The file goes through the crash-safe store (`finestep_store`): written to a temporary
//! file, flushed and renamed over the old one, the old one kept as `FILE.bak`, sealed by
//! a last comment line (`# finestep-store v1 ...`) that LinuxCNC's reader skips as it
//! skips every line that is not `index value`. A hand-written or LinuxCNC-written file
//! (no seal) is read as it is; a missing file starts from no parameters (all zero, G54)
//! and is created at the end.

use std::path::{Path, PathBuf};

use anyhow::Context;
use finestep_gcode::Parameters;
use finestep_store::{LoadOptions, OsFs, Source, StoreError};

/// The parameter file named by a configuration loaded from `config_path` (relative paths
/// from its folder); none for the built-in machine or a configuration without one.
pub fn path_of(parameter_file: Option<&Path>, config_path: Option<&Path>) -> Option<PathBuf> {
    let file = parameter_file?;
    Some(match config_path.and_then(Path::parent) {
        Some(dir) if file.is_relative() => dir.join(file),
        _ => file.to_path_buf(),
    })
}

/// Reads the parameter file at `path`: its parameters, or none when it does not exist.
/// A fallback to the last good copy is printed with what was wrong with the file.
pub fn load(path: &Path) -> anyhow::Result<Parameters> {
    let name = path.display().to_string();
    let parse = |bytes: &[u8]| {
        let text = std::str::from_utf8(bytes).map_err(|e| format!("not UTF-8 text: {e}"))?;
        Parameters::read(text).map_err(|e| e.to_string())
    };
    match finestep_store::load(&mut OsFs, path, LoadOptions { accept_unsealed: true }, parse) {
        Ok(loaded) => {
            if loaded.source == Source::LastGood {
                for problem in &loaded.problems {
                    eprintln!("warning: {problem}");
                }
                eprintln!(
                    "warning: {name}: using the last good copy ({}, generation {})",
                    finestep_store::backup_path(path).display(),
                    loaded.generation
                );
            }
            Ok(loaded.value)
        }
        Err(StoreError::NotFound { .. }) => {
            eprintln!("note: parameter file {name} does not exist yet: starting from none (G54, no offsets)");
            Ok(Parameters::default())
        }
        Err(e) => Err(e).with_context(|| format!("reading the parameter file {name}")),
    }
}

/// Writes `parameters` to `path` crash-safe (LinuxCNC's format, sealed); the store's
/// generation of the file written.
pub fn save(path: &Path, parameters: &Parameters) -> anyhow::Result<u64> {
    finestep_store::save(&mut OsFs, path, parameters.to_text().as_bytes())
        .with_context(|| format!("writing the parameter file {}", path.display()))
}
