//! `finestep sim-chip SOCKET`: the simulated chip served on a Unix socket at the byte
//! level of the SPI link (the framing of [`finestep_host::sim_link`]), so that a host
//! tool on `--bus sim:SOCKET` runs the code it runs on spidev. The chip is reset once at
//! start and keeps its state across connections, as a board does; its time advances
//! only by the clients' frames and waits.

use std::os::unix::fs::FileTypeExt;
use std::os::unix::net::UnixListener;
use std::path::Path;

use anyhow::{bail, Context};
use finestep_cosim::rtl_top_params;
use finestep_host::frame::{self, Command, FRAME_CRC};
use finestep_host::{regs, sim_link, BusError, SpiTransfer};

/// What serves the chip.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Target {
    /// The Verilated RTL in lockstep with the reference model, compared every clock.
    Lockstep,
    /// The reference model alone (faster; nothing to compare against).
    Model,
}

/// A fault the server injects, for tests of the tools that must notice it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Fault {
    /// ID reads 0xDEADBEEF (with a valid CRC): not a finestep core.
    WrongIdentity,
    /// The loopback encoder is unplugged (implies `--plant`): it never counts.
    DeadEncoder,
}

/// The ID a chip with [`Fault::WrongIdentity`] answers.
pub const WRONG_ID: u32 = 0xDEAD_BEEF;

/// Rewrites the ID word of every READ frame that covers it, CRC included.
struct WrongIdentity<L> {
    link: L,
}

impl<L: SpiTransfer> SpiTransfer for WrongIdentity<L> {
    fn transfer(&mut self, tx: &[u8]) -> Result<Vec<u8>, BusError> {
        let mut rx = self.link.transfer(tx)?;
        let header = frame::HEADER_BYTES;
        if tx.len() >= header + 6 && tx[0] == Command::Read.code() && rx.len() == tx.len() {
            let (addr, count) = (usize::from(tx[1]), usize::from(tx[2]));
            let id = usize::from(regs::id::ADDR);
            if (addr..addr + count).contains(&id) && header + 4 * count + 2 == tx.len() {
                let at = header + 4 * (id - addr);
                rx[at..at + 4].copy_from_slice(&WRONG_ID.to_be_bytes());
                let mut digest = FRAME_CRC.digest();
                digest.update(&tx[..header]);
                digest.update(&rx[header..rx.len() - 2]);
                let crc = digest.finalize().to_be_bytes();
                let end = rx.len();
                rx[end - 2..].copy_from_slice(&crc);
            }
        }
        Ok(rx)
    }

    fn wait(&mut self, clocks: u64) -> Result<(), BusError> {
        self.link.wait(clocks)
    }

    fn drive_estop(&mut self, level: bool) -> Result<bool, BusError> {
        self.link.drive_estop(level)
    }
}

/// Serves the chip on `socket` (a stale socket file there is replaced) until killed,
/// or until the first client leaves with `once`; with `plant`, the self-test's loopback
/// machine is on its pins ([`crate::bus::loopback_plant`]).
pub fn run(socket: &Path, target: Target, plant: bool, faults: &[Fault], once: bool) -> anyhow::Result<()> {
    if let Ok(meta) = std::fs::symlink_metadata(socket) {
        if !meta.file_type().is_socket() {
            bail!("{} exists and is not a socket", socket.display());
        }
        std::fs::remove_file(socket).with_context(|| format!("removing the stale socket {}", socket.display()))?;
    }
    let dead_encoder = faults.contains(&Fault::DeadEncoder);
    let plant = if plant || dead_encoder {
        Some(crate::bus::loopback_plant(rtl_top_params().n_axes, dead_encoder)?)
    } else {
        None
    };
    let mut link = crate::bus::sim_link(target == Target::Lockstep, "sim-chip", plant)?;
    for fault in faults {
        link = match fault {
            Fault::WrongIdentity => Box::new(WrongIdentity { link }),
            Fault::DeadEncoder => link,
        };
    }
    let listener = UnixListener::bind(socket).with_context(|| format!("binding {}", socket.display()))?;
    println!("finestep sim-chip: {target:?} chip on {} (faults: {faults:?})", socket.display());
    for stream in listener.incoming() {
        let mut stream = stream.context("accepting a client")?;
        if let Err(e) = sim_link::serve(&mut stream, &mut link) {
            eprintln!("finestep sim-chip: client dropped: {e}");
        }
        if once {
            break;
        }
    }
    let _ = std::fs::remove_file(socket);
    Ok(())
}
