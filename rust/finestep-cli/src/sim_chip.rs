//! `finestep sim-chip SOCKET`: the simulated chip served on a Unix socket at the byte
//! level of the SPI link (the framing of [`finestep_host::sim_link`]), so that a host
//! tool on `--bus sim:SOCKET` runs the code it runs on spidev. The chip is reset once at
//! start and keeps its state across connections, as a board does; its time advances
//! only by the clients' frames and waits. It measures the step pins' drive timing every
//! clock it simulates ([`crate::bus::measured_sim_link`]) and answers the link's
//! pin-timing request with the figures so far.

use std::os::unix::fs::FileTypeExt;
use std::os::unix::net::UnixListener;
use std::path::Path;

use anyhow::{bail, Context};
use finestep_cosim::rtl_top_params;
use finestep_host::frame::{self, Command, FRAME_CRC};
use finestep_host::{regs, sim_link, BusError, SpiTransfer};
use finestep_plant::{CountsPerStep, Plant, PlantConfig, LAGGING_SEED};

/// What serves the chip.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Target {
    /// The Verilated RTL in lockstep with the reference model, compared every clock.
    Lockstep,
    /// The reference model alone (faster; nothing to compare against).
    Model,
}

/// The machine on the chip's pins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Machine {
    /// Nothing: the feedback pins idle.
    None,
    /// The self-test's loopback machine ([`crate::bus::loopback_plant`]).
    Loopback,
    /// The closed-loop machine of `finestep_plant::PlantConfig::lagging`: a drive
    /// lagging by `tau` clocks on every axis, a grating of `counts_per_step` on every
    /// axis with an encoder channel.
    Lagging {
        /// The drives' time constant, core clocks.
        tau: u64,
        /// The gratings' counts per step.
        counts_per_step: u32,
    },
}

/// A fault the server injects, for tests of the tools that must notice it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Fault {
    /// ID reads 0xDEADBEEF (with a valid CRC): not a finestep core.
    WrongIdentity,
    /// The loopback encoder is unplugged (implies `--plant`): it never counts.
    DeadEncoder,
    /// Bit 2 of every register read after the identity block is stuck at 1.
    StuckBit,
}

/// The ID a chip with [`Fault::WrongIdentity`] answers.
pub const WRONG_ID: u32 = 0xDEAD_BEEF;

/// The register-file bit that [`Fault::StuckBit`] holds at 1 in every register read
/// after the identity block (ID, VERSION, CAPS, CLOCK_HZ).
pub const STUCK_BIT: u32 = 1 << 2;

/// Rewrites the words of every READ answer through `rewrite(address, word)`, CRC
/// included (a fault inside the chip, not on the wire).
struct ReadRewrite<L> {
    link: L,
    rewrite: fn(u8, u32) -> u32,
}

impl<L: SpiTransfer> SpiTransfer for ReadRewrite<L> {
    fn transfer(&mut self, tx: &[u8]) -> Result<Vec<u8>, BusError> {
        let mut rx = self.link.transfer(tx)?;
        let header = frame::HEADER_BYTES;
        let count = tx.get(2).map_or(0, |&c| usize::from(c));
        if tx.first() == Some(&Command::Read.code()) && rx.len() == tx.len() && tx.len() == header + 4 * count + 2 {
            for (i, word) in rx[header..header + 4 * count].chunks_exact_mut(4).enumerate() {
                let addr = tx[1].wrapping_add(i as u8);
                let value = (self.rewrite)(addr, u32::from_be_bytes([word[0], word[1], word[2], word[3]]));
                word.copy_from_slice(&value.to_be_bytes());
            }
            let mut digest = FRAME_CRC.digest();
            digest.update(&tx[..header]);
            digest.update(&rx[header..rx.len() - 2]);
            let crc = digest.finalize().to_be_bytes();
            let end = rx.len();
            rx[end - 2..].copy_from_slice(&crc);
        }
        Ok(rx)
    }

    fn wait(&mut self, clocks: u64) -> Result<(), BusError> {
        self.link.wait(clocks)
    }

    fn drive_estop(&mut self, level: bool) -> Result<bool, BusError> {
        self.link.drive_estop(level)
    }

    fn turn_wheel(&mut self, edges: i64) -> Result<bool, BusError> {
        self.link.turn_wheel(edges)
    }

    fn pin_timing(&mut self) -> Result<Option<finestep_host::PinTimingReport>, BusError> {
        self.link.pin_timing()
    }
}

fn wrong_identity(addr: u8, word: u32) -> u32 {
    if addr == regs::id::ADDR {
        WRONG_ID
    } else {
        word
    }
}

fn stuck_bit(addr: u8, word: u32) -> u32 {
    if addr > regs::clock_hz::ADDR {
        word | STUCK_BIT
    } else {
        word
    }
}

/// Serves the chip on `socket` (a stale socket file there is replaced) until killed,
/// or until the first client leaves with `once`, with `machine` on its pins.
pub fn run(socket: &Path, target: Target, machine: Machine, faults: &[Fault], once: bool) -> anyhow::Result<()> {
    if let Ok(meta) = std::fs::symlink_metadata(socket) {
        if !meta.file_type().is_socket() {
            bail!("{} exists and is not a socket", socket.display());
        }
        std::fs::remove_file(socket).with_context(|| format!("removing the stale socket {}", socket.display()))?;
    }
    let dead_encoder = faults.contains(&Fault::DeadEncoder);
    let params = rtl_top_params();
    let plant = match machine {
        Machine::Lagging { tau, counts_per_step } => {
            let config =
                PlantConfig::lagging(params.n_axes, params.n_enc, tau, CountsPerStep::integer(counts_per_step)?);
            Some(Plant::new(config, LAGGING_SEED)?)
        }
        Machine::Loopback => Some(crate::bus::loopback_plant(params.n_axes, dead_encoder)?),
        Machine::None if dead_encoder => Some(crate::bus::loopback_plant(params.n_axes, dead_encoder)?),
        Machine::None => None,
    };
    let mut link = crate::bus::measured_sim_link(target == Target::Lockstep, "sim-chip", plant)?;
    for fault in faults {
        link = match fault {
            Fault::WrongIdentity => Box::new(ReadRewrite { link, rewrite: wrong_identity }),
            Fault::StuckBit => Box::new(ReadRewrite { link, rewrite: stuck_bit }),
            Fault::DeadEncoder => link,
        };
    }
    // Bound and listening under a sibling name, then renamed into place: a client that
    // waits for the socket file to appear (the tests, linuxcnc_run.sh) would otherwise
    // meet it between bind and listen and be refused.
    let mut binding = socket.as_os_str().to_owned();
    binding.push(".binding");
    let binding = std::path::PathBuf::from(binding);
    let _ = std::fs::remove_file(&binding);
    let listener = UnixListener::bind(&binding).with_context(|| format!("binding {}", binding.display()))?;
    std::fs::rename(&binding, socket)
        .with_context(|| format!("moving {} to {}", binding.display(), socket.display()))?;
    println!(
        "finestep sim-chip: {target:?} chip on {} ({machine:?} on its pins; faults: {faults:?})",
        socket.display()
    );
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
