//! Crash-safe files for finestep's parameters and machine configuration.
//!
//! A file written here survives a crash or a power loss at any instant: a later
//! [`load`] reads either the previous content or the new one, whole, and never a torn or
//! silently wrong one. How:
//!
//! - **Atomic replace**: the new content goes to `FILE.tmp`, is flushed (`fsync`), renamed
//!   over `FILE`, and the directory is flushed. A crash leaves `FILE` as it was or as it
//!   is now; never half of each.
//! - **A seal**: the last line of the file is a comment (`# finestep-store v1
//!   generation=G length=L crc32c=C`) that says how long the content is, which save
//!   wrote it, and its CRC-32C (over the content and the generation). A TOML file stays
//!   TOML (the seal is a comment): a sealed machine configuration loads as before.
//! - **The last good copy**: before a save replaces `FILE`, a `FILE` that checks out is
//!   copied to `FILE.bak` the same atomic way. When `FILE` is missing, torn, altered or
//!   rejected by the caller's parser, [`load`] reads `FILE.bak` and says so
//!   ([`Source::LastGood`] with the [`Problem`]s found): the fallback is reported, never
//!   silent.
//!
//! A file without a seal (written by hand) is accepted only where the caller asks for
//! it ([`LoadOptions::accept_unsealed`]) and no last good copy exists (a store-managed
//! file without its seal is torn, not hand-written).
//!
//! Every file operation goes through [`Fs`], so a test can crash the writer at each
//! step ([`sim::SimFs`] loses what was not flushed, as a power loss does); [`OsFs`] is
//! the real file system.
//!
//! ```
//! use finestep_store::{load, save, LoadOptions, OsFs, Source};
//! let dir = std::env::temp_dir().join(format!("finestep-store-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir).unwrap();
//! let path = dir.join("machine.toml");
//! save(&mut OsFs, &path, b"period_ms = 1.0\n").unwrap();
//! save(&mut OsFs, &path, b"period_ms = 2.0\n").unwrap();
//! let parse = |b: &[u8]| String::from_utf8(b.to_vec()).map_err(|e| e.to_string());
//! let loaded = load(&mut OsFs, &path, LoadOptions::default(), parse).unwrap();
//! assert_eq!((loaded.value.as_str(), loaded.generation, loaded.source), ("period_ms = 2.0\n", 2, Source::Current));
//! // The disk flips a bit: the last good copy answers, and the problem is named.
//! let mut bytes = std::fs::read(&path).unwrap();
//! bytes[12] ^= 1;
//! std::fs::write(&path, bytes).unwrap();
//! let loaded = load(&mut OsFs, &path, LoadOptions::default(), parse).unwrap();
//! assert_eq!((loaded.value.as_str(), loaded.source), ("period_ms = 1.0\n", Source::LastGood));
//! assert!(loaded.problems[0].to_string().contains("checksum"));
//! std::fs::remove_dir_all(&dir).unwrap();
//! ```

#![warn(missing_docs)]

pub mod sim;

use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

/// CRC-32C (Castagnoli), the checksum of the seal.
const CRC32C: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISCSI);

/// The seal line's first words.
const SEAL_PREFIX: &str = "# finestep-store v1 ";

/// The file operations a save and a load use.
pub trait Fs {
    /// The file's bytes, or `None` when it does not exist.
    fn read(&mut self, path: &Path) -> io::Result<Option<Vec<u8>>>;
    /// Creates or truncates the file and writes `bytes` (not yet flushed).
    fn write(&mut self, path: &Path, bytes: &[u8]) -> io::Result<()>;
    /// Flushes the file's content to the disk (`fsync`).
    fn sync(&mut self, path: &Path) -> io::Result<()>;
    /// Renames `from` to `to`, replacing `to` atomically.
    fn rename(&mut self, from: &Path, to: &Path) -> io::Result<()>;
    /// Flushes the directory (its entries: creations and renames) to the disk.
    fn sync_dir(&mut self, dir: &Path) -> io::Result<()>;
}

/// The real file system.
#[derive(Clone, Copy, Debug, Default)]
pub struct OsFs;

impl Fs for OsFs {
    fn read(&mut self, path: &Path) -> io::Result<Option<Vec<u8>>> {
        match std::fs::read(path) {
            Ok(bytes) => Ok(Some(bytes)),
            Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(e),
        }
    }

    fn write(&mut self, path: &Path, bytes: &[u8]) -> io::Result<()> {
        std::fs::write(path, bytes)
    }

    fn sync(&mut self, path: &Path) -> io::Result<()> {
        std::fs::File::open(path)?.sync_all()
    }

    fn rename(&mut self, from: &Path, to: &Path) -> io::Result<()> {
        std::fs::rename(from, to)
    }

    fn sync_dir(&mut self, dir: &Path) -> io::Result<()> {
        std::fs::File::open(dir)?.sync_all()
    }
}

/// Which copy a [`load`] read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// The file itself.
    Current,
    /// The last good copy (`FILE.bak`): the file was missing, torn, altered or rejected.
    LastGood,
    /// The file, without a seal (written by hand; see [`LoadOptions::accept_unsealed`]).
    Unsealed,
}

impl fmt::Display for Source {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Source::Current => "the file",
            Source::LastGood => "the last good copy",
            Source::Unsealed => "the file (unsealed, as written by hand)",
        })
    }
}

/// What is wrong with one copy.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Corruption {
    /// The copy does not exist.
    #[error("missing")]
    Missing,
    /// It could not be read.
    #[error("unreadable: {0}")]
    Unreadable(String),
    /// It has no seal line (torn, or not written by the store).
    #[error("no seal (torn, or not written by finestep-store)")]
    NoSeal,
    /// The seal line does not parse.
    #[error("malformed seal: {0}")]
    BadSeal(String),
    /// The content is not as long as the seal says.
    #[error("length {actual} bytes, the seal says {sealed}")]
    Length {
        /// From the seal.
        sealed: usize,
        /// Found.
        actual: usize,
    },
    /// The content's checksum differs from the seal's.
    #[error("checksum crc32c {actual:08x}, the seal says {sealed:08x}")]
    Checksum {
        /// From the seal.
        sealed: u32,
        /// Computed.
        actual: u32,
    },
    /// The seal checks out but the caller's parser rejects the content.
    #[error("rejected: {0}")]
    Rejected(String),
}

/// A copy and what is wrong with it.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}: {kind}", path.display())]
pub struct Problem {
    /// The copy's path.
    pub path: PathBuf,
    /// What is wrong.
    pub kind: Corruption,
}

/// Why a save or a load failed.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// A file operation failed.
    #[error("{op} {}: {source}", path.display())]
    Io {
        /// The operation.
        op: &'static str,
        /// The path.
        path: PathBuf,
        /// The error.
        source: io::Error,
    },
    /// Neither the file nor its last good copy exists.
    #[error("{}: no such file (nor a last good copy {})", path.display(), backup_path(path).display())]
    NotFound {
        /// The file.
        path: PathBuf,
    },
    /// No copy could be used.
    #[error("{}: no good copy: {}", path.display(), problems.iter().map(ToString::to_string).collect::<Vec<_>>().join("; "))]
    NoGoodCopy {
        /// The file.
        path: PathBuf,
        /// What is wrong with each copy.
        problems: Vec<Problem>,
    },
    /// The path names no file (no file name).
    #[error("{}: not a file path", path.display())]
    NotAFile {
        /// The path.
        path: PathBuf,
    },
}

/// How [`load`] treats a file without a seal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Accept a file without a seal when no last good copy exists (a file written by
    /// hand), as [`Source::Unsealed`].
    pub accept_unsealed: bool,
}

/// What a [`load`] read.
#[derive(Clone, Debug, PartialEq)]
pub struct Loaded<T> {
    /// The parsed content.
    pub value: T,
    /// The save that wrote it (1 for the first; 0 for an unsealed file).
    pub generation: u64,
    /// Which copy it came from.
    pub source: Source,
    /// What was wrong with the copies passed over (empty when the file was good).
    pub problems: Vec<Problem>,
}

/// The last good copy of `path`: `FILE.bak` beside it.
pub fn backup_path(path: &Path) -> PathBuf {
    with_suffix(path, ".bak")
}

fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(suffix);
    path.with_file_name(name)
}

fn checksum(payload: &[u8], generation: u64) -> u32 {
    let mut digest = CRC32C.digest();
    digest.update(payload);
    digest.update(&generation.to_le_bytes());
    digest.finalize()
}

/// The bytes of a sealed file: `payload`, a newline if it does not end in one, and the
/// seal line.
pub fn seal(payload: &[u8], generation: u64) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(payload.len() + 80);
    bytes.extend_from_slice(payload);
    if !payload.is_empty() && !payload.ends_with(b"\n") {
        bytes.push(b'\n');
    }
    let line = format!(
        "{SEAL_PREFIX}generation={generation} length={} crc32c={:08x}\n",
        payload.len(),
        checksum(payload, generation)
    );
    bytes.extend_from_slice(line.as_bytes());
    bytes
}

/// The payload and generation of a sealed file's bytes, or what is wrong with them.
pub fn unseal(bytes: &[u8]) -> Result<(&[u8], u64), Corruption> {
    let body = bytes.strip_suffix(b"\n").ok_or(Corruption::NoSeal)?;
    let start = body.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    let line = std::str::from_utf8(&body[start..]).map_err(|_| Corruption::NoSeal)?;
    let fields = line.strip_prefix(SEAL_PREFIX).ok_or(Corruption::NoSeal)?;
    let mut words = fields.split(' ');
    let mut field = |key: &str| -> Result<&str, Corruption> {
        let word = words.next().ok_or_else(|| Corruption::BadSeal(format!("no {key}")))?;
        word.strip_prefix(key)
            .and_then(|w| w.strip_prefix('='))
            .ok_or_else(|| Corruption::BadSeal(format!("expected {key}=, found {word:?}")))
    };
    // Numbers only in the form `seal` writes them (no sign, no leading zero, lower-case
    // hex): an altered seal never passes for the same one.
    let bad = |what: &str, text: &str| Corruption::BadSeal(format!("{what} {text:?}"));
    let decimal = |what: &str, text: &str| -> Result<u64, Corruption> {
        text.parse::<u64>().ok().filter(|n| n.to_string() == text).ok_or_else(|| bad(what, text))
    };
    let generation = decimal("generation", field("generation")?)?;
    let length_text = field("length")?;
    let sealed = usize::try_from(decimal("length", length_text)?).map_err(|_| bad("length", length_text))?;
    let crc_text = field("crc32c")?;
    let crc = u32::from_str_radix(crc_text, 16)
        .ok()
        .filter(|c| format!("{c:08x}") == crc_text)
        .ok_or_else(|| bad("crc32c", crc_text))?;
    if words.next().is_some() {
        return Err(Corruption::BadSeal("words after crc32c".into()));
    }
    // The content, and the newline the seal put after it if it lacked one.
    let payload = &bytes[..start];
    let payload = match payload.len().checked_sub(sealed) {
        Some(0) => payload,
        Some(1) if sealed > 0 && payload.ends_with(b"\n") && !payload[..sealed].ends_with(b"\n") => &payload[..sealed],
        _ => return Err(Corruption::Length { sealed, actual: payload.len() }),
    };
    let actual = checksum(payload, generation);
    if actual != crc {
        return Err(Corruption::Checksum { sealed: crc, actual });
    }
    Ok((payload, generation))
}

fn io_error(op: &'static str, path: &Path) -> impl FnOnce(io::Error) -> StoreError {
    let path = path.to_path_buf();
    move |source| StoreError::Io { op, path, source }
}

/// The directory holding `path` (`.` for a bare file name).
fn parent_dir(path: &Path) -> Result<PathBuf, StoreError> {
    if path.file_name().is_none() {
        return Err(StoreError::NotAFile { path: path.to_path_buf() });
    }
    Ok(match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.to_path_buf(),
        _ => PathBuf::from("."),
    })
}

/// Writes `bytes` to `path` atomically: `path.tmp`, flushed, renamed over `path`, the
/// directory flushed.
fn replace(fs: &mut impl Fs, path: &Path, dir: &Path, bytes: &[u8]) -> Result<(), StoreError> {
    let tmp = with_suffix(path, ".tmp");
    fs.write(&tmp, bytes).map_err(io_error("writing", &tmp))?;
    fs.sync(&tmp).map_err(io_error("flushing", &tmp))?;
    fs.rename(&tmp, path).map_err(io_error("renaming to", path))?;
    fs.sync_dir(dir).map_err(io_error("flushing the directory", dir))?;
    Ok(())
}

/// Saves `payload` to `path` crash-safe (see the crate documentation) and returns its
/// generation: one more than the newest good copy's. A good `path` becomes the last
/// good copy first.
pub fn save(fs: &mut impl Fs, path: &Path, payload: &[u8]) -> Result<u64, StoreError> {
    let dir = parent_dir(path)?;
    let backup = backup_path(path);
    let current = fs.read(path).map_err(io_error("reading", path))?;
    let current_generation = current.as_deref().and_then(|b| unseal(b).ok()).map(|(_, g)| g);
    let previous = match current_generation {
        Some(g) => g,
        None => fs.read(&backup).ok().flatten().as_deref().and_then(|b| unseal(b).ok()).map_or(0, |(_, g)| g),
    };
    if let (Some(bytes), Some(_)) = (&current, current_generation) {
        replace(fs, &backup, &dir, bytes)?;
    }
    let generation = previous + 1;
    replace(fs, path, &dir, &seal(payload, generation))?;
    Ok(generation)
}

/// What is wrong with a copy, and its bytes when they were read but carry no good seal.
type Rejection = (Corruption, Option<Vec<u8>>);

/// One copy: its payload parsed, or what is wrong with it.
fn check<T>(fs: &mut impl Fs, path: &Path, parse: &impl Fn(&[u8]) -> Result<T, String>) -> Result<(T, u64), Rejection> {
    let bytes = match fs.read(path) {
        Ok(Some(bytes)) => bytes,
        Ok(None) => return Err((Corruption::Missing, None)),
        Err(e) => return Err((Corruption::Unreadable(e.to_string()), None)),
    };
    let (payload, generation) = match unseal(&bytes) {
        Ok(ok) => ok,
        Err(kind) => return Err((kind, Some(bytes))),
    };
    parse(payload).map(|value| (value, generation)).map_err(|why| (Corruption::Rejected(why), None))
}

/// Loads `path`, parsed by `parse`: the file if it checks out, else its last good copy
/// (with the problems found), else an error naming what is wrong with each.
pub fn load<T>(
    fs: &mut impl Fs,
    path: &Path,
    options: LoadOptions,
    parse: impl Fn(&[u8]) -> Result<T, String>,
) -> Result<Loaded<T>, StoreError> {
    parent_dir(path)?;
    let primary = match check(fs, path, &parse) {
        Ok((value, generation)) => {
            return Ok(Loaded { value, generation, source: Source::Current, problems: Vec::new() })
        }
        Err(e) => e,
    };
    let backup = backup_path(path);
    let mut problems = vec![Problem { path: path.to_path_buf(), kind: primary.0.clone() }];
    match check(fs, &backup, &parse) {
        Ok((value, generation)) => Ok(Loaded { value, generation, source: Source::LastGood, problems }),
        Err((Corruption::Missing, _)) => match primary {
            (Corruption::Missing, _) => Err(StoreError::NotFound { path: path.to_path_buf() }),
            (Corruption::NoSeal, Some(bytes)) if options.accept_unsealed => match parse(&bytes) {
                Ok(value) => Ok(Loaded { value, generation: 0, source: Source::Unsealed, problems: Vec::new() }),
                Err(why) => {
                    problems[0].kind = Corruption::Rejected(why);
                    Err(StoreError::NoGoodCopy { path: path.to_path_buf(), problems })
                }
            },
            _ => {
                problems.push(Problem { path: backup, kind: Corruption::Missing });
                Err(StoreError::NoGoodCopy { path: path.to_path_buf(), problems })
            }
        },
        Err((kind, _)) => {
            problems.push(Problem { path: backup, kind });
            Err(StoreError::NoGoodCopy { path: path.to_path_buf(), problems })
        }
    }
}

#[cfg(test)]
mod tests;
