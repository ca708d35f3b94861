//! A simulated file system that crashes on request and then loses what a power loss
//! may lose: file content not flushed (`fsync`) and directory entries (creations,
//! renames) whose directory was not flushed.
//!
//! [`SimFs::crash_after`] lets a number of operations succeed, then every further one
//! fails (the writer died there). [`SimFs::power_loss`] then decides, from a seeded
//! choice, what reached the disk: for every file with unflushed content, the old
//! content, the new one, or a torn prefix of the new one; for the directory, the entries
//! as last flushed or as they are now (a rename or creation persisted or not). What was
//! flushed is never lost. The model holds one directory's entries (every path the
//! store touches lies in one directory).

use std::collections::BTreeMap;
use std::io;
use std::path::{Path, PathBuf};

use crate::Fs;

/// A file's content: what is on the disk, and what was written since and not flushed.
#[derive(Clone, Debug, Default)]
struct Inode {
    durable: Vec<u8>,
    pending: Option<Vec<u8>>,
}

impl Inode {
    fn current(&self) -> &[u8] {
        self.pending.as_deref().unwrap_or(&self.durable)
    }
}

/// The simulated file system (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct SimFs {
    inodes: Vec<Inode>,
    /// Entries as the running program sees them.
    entries: BTreeMap<PathBuf, usize>,
    /// Entries as last flushed.
    durable_entries: BTreeMap<PathBuf, usize>,
    /// Operations left before the crash (`None`: no crash planned).
    ops_left: Option<usize>,
    /// Operations done.
    ops: usize,
}

fn crashed() -> io::Error {
    io::Error::other("simulated crash")
}

impl SimFs {
    /// An empty file system.
    pub fn new() -> SimFs {
        SimFs::default()
    }

    /// The next `ops` operations succeed, every one after them fails.
    pub fn crash_after(&mut self, ops: usize) {
        self.ops_left = Some(ops);
    }

    /// Operations done so far (to count a save's steps).
    pub fn ops(&self) -> usize {
        self.ops
    }

    /// The power fails: what was not flushed is kept, lost or torn as `choice` draws
    /// (`choice(n)` answers in `0..n`). The crash plan ends; the disk is as after a
    /// reboot.
    pub fn power_loss(&mut self, mut choice: impl FnMut(usize) -> usize) {
        if choice(2) == 0 {
            self.entries = self.durable_entries.clone();
        } else {
            self.durable_entries = self.entries.clone();
        }
        for inode in &mut self.inodes {
            if let Some(new) = inode.pending.take() {
                inode.durable = match choice(3) {
                    0 => std::mem::take(&mut inode.durable),
                    1 => new,
                    _ => new[..choice(new.len() + 1)].to_vec(),
                };
            }
        }
        self.ops_left = None;
    }

    /// Puts a flushed file directly (test set-up, or a disk fault in place).
    pub fn put(&mut self, path: &Path, bytes: &[u8]) {
        let inode = self.inodes.len();
        self.inodes.push(Inode { durable: bytes.to_vec(), pending: None });
        self.entries.insert(path.to_path_buf(), inode);
        self.durable_entries.insert(path.to_path_buf(), inode);
    }

    /// The file's current content, as the running program reads it.
    pub fn get(&self, path: &Path) -> Option<&[u8]> {
        self.entries.get(path).map(|&i| self.inodes[i].current())
    }

    fn step(&mut self) -> io::Result<()> {
        match &mut self.ops_left {
            Some(0) => return Err(crashed()),
            Some(left) => *left -= 1,
            None => {}
        }
        self.ops += 1;
        Ok(())
    }
}

impl Fs for SimFs {
    fn read(&mut self, path: &Path) -> io::Result<Option<Vec<u8>>> {
        self.step()?;
        Ok(self.get(path).map(<[u8]>::to_vec))
    }

    fn write(&mut self, path: &Path, bytes: &[u8]) -> io::Result<()> {
        self.step()?;
        match self.entries.get(path) {
            Some(&i) => self.inodes[i].pending = Some(bytes.to_vec()),
            None => {
                let i = self.inodes.len();
                self.inodes.push(Inode { durable: Vec::new(), pending: Some(bytes.to_vec()) });
                self.entries.insert(path.to_path_buf(), i);
            }
        }
        Ok(())
    }

    fn sync(&mut self, path: &Path) -> io::Result<()> {
        self.step()?;
        let &i = self.entries.get(path).ok_or_else(|| io::Error::from(io::ErrorKind::NotFound))?;
        if let Some(new) = self.inodes[i].pending.take() {
            self.inodes[i].durable = new;
        }
        Ok(())
    }

    fn rename(&mut self, from: &Path, to: &Path) -> io::Result<()> {
        self.step()?;
        let i = self.entries.remove(from).ok_or_else(|| io::Error::from(io::ErrorKind::NotFound))?;
        self.entries.insert(to.to_path_buf(), i);
        Ok(())
    }

    fn sync_dir(&mut self, _dir: &Path) -> io::Result<()> {
        self.step()?;
        self.durable_entries = self.entries.clone();
        Ok(())
    }
}
