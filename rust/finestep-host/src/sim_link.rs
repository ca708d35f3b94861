//! The SPI link over a Unix socket: a simulated chip served by `finestep sim-chip
//! SOCKET` and [`SimSocket`], the [`SpiTransfer`] that talks to it. A host tool on a
//! socket runs the same code as on [`crate::spidev::Spidev`]; only this trait differs.
//!
//! The framing, one request answered by one reply, every integer little-endian:
//!
//! | request | bytes |
//! | --- | --- |
//! | transfer | `b'T'`, `len: u32`, `len` bytes sent on MOSI in one chip-select frame |
//! | wait | `b'W'`, `8: u32`, `clocks: u64` core clocks to let pass |
//! | E-stop | `b'E'`, `1: u32`, the level to drive on the E-stop input (0 or 1) |
//! | hand wheel | `b'M'`, `8: u32`, `edges: i64` quadrature edges to turn the wheel by while clocks pass |
//! | pin timing | `b'P'`, `0: u32`: what the chip measured at its step pins ([`PinTimingReport::to_bytes`]) |
//!
//! | reply | bytes |
//! | --- | --- |
//! | done | `0`, `len: u32`, the `len` bytes received on MISO (0 for a wait; for an E-stop or a wheel turn, one byte: 1 when driven) |
//! | failed | `1`, `len: u32`, a UTF-8 message (a lockstep mismatch, an unknown op) |
//!
//! Simulated time advances only by transfers and waits: a result never depends on how
//! loaded the machine running the server is.
//!
//! ```no_run
//! use finestep_host::{sim_link::SimSocket, Machine, SpiBus};
//! let link = SimSocket::connect("/tmp/chip.sock")?;
//! let machine = Machine::connect(SpiBus::new(link, 4))?;
//! println!("{:?}", machine.caps());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};

use finestep_interface::pin_timing::PinTimingReport;

use crate::spi::SpiTransfer;
use crate::BusError;

/// Request op: one chip-select frame.
pub const OP_TRANSFER: u8 = b'T';
/// Request op: let core clocks pass.
pub const OP_WAIT: u8 = b'W';
/// Request op: drive the E-stop input.
pub const OP_ESTOP: u8 = b'E';
/// Request op: turn the hand wheel.
pub const OP_WHEEL: u8 = b'M';
/// Request op: the step pins' timing measured so far.
pub const OP_PIN_TIMING: u8 = b'P';
/// Reply status: done.
pub const REPLY_DONE: u8 = 0;
/// Reply status: failed, the payload is the message.
pub const REPLY_FAILED: u8 = 1;
/// The longest payload either side accepts (a FIFO frame of 255 records of 8 axes is
/// under 9 KiB).
pub const MAX_PAYLOAD: u32 = 1 << 20;

/// Why the socket link failed.
#[derive(Debug, thiserror::Error)]
pub enum SimLinkError {
    /// Nothing answers at the socket (no server, or not a socket).
    #[error("sim:{path}: cannot connect: {source}")]
    Connect {
        /// The socket path.
        path: PathBuf,
        /// The error of `connect`.
        source: std::io::Error,
    },
    /// Reading or writing the socket failed (the other side went away).
    #[error("socket: {0}")]
    Io(#[from] std::io::Error),
    /// The other side broke the framing.
    #[error("socket protocol: {0}")]
    Protocol(String),
    /// The server could not carry out the request.
    #[error("the simulated chip failed: {0}")]
    Server(String),
}

impl From<SimLinkError> for BusError {
    fn from(error: SimLinkError) -> Self {
        BusError::Transport(Box::new(error))
    }
}

fn write_message(stream: &mut impl Write, head: u8, payload: &[u8]) -> Result<(), SimLinkError> {
    let len = u32::try_from(payload.len()).ok().filter(|&n| n <= MAX_PAYLOAD);
    let len = len.ok_or_else(|| SimLinkError::Protocol(format!("a payload of {} bytes", payload.len())))?;
    let mut bytes = Vec::with_capacity(5 + payload.len());
    bytes.push(head);
    bytes.extend_from_slice(&len.to_le_bytes());
    bytes.extend_from_slice(payload);
    stream.write_all(&bytes)?;
    stream.flush()?;
    Ok(())
}

/// Reads one message; `None` at a clean end of stream before its first byte.
fn read_message(stream: &mut impl Read) -> Result<Option<(u8, Vec<u8>)>, SimLinkError> {
    let mut head = [0u8; 5];
    match stream.read(&mut head[..1]) {
        Ok(0) => return Ok(None),
        Ok(_) => {}
        Err(e) if e.kind() == ErrorKind::ConnectionReset => return Ok(None),
        Err(e) => return Err(e.into()),
    }
    stream.read_exact(&mut head[1..])?;
    let len = u32::from_le_bytes([head[1], head[2], head[3], head[4]]);
    if len > MAX_PAYLOAD {
        return Err(SimLinkError::Protocol(format!("a payload of {len} bytes (at most {MAX_PAYLOAD})")));
    }
    let mut payload = vec![0u8; len as usize];
    stream.read_exact(&mut payload)?;
    Ok(Some((head[0], payload)))
}

/// [`SpiTransfer`] to a simulated chip served on a Unix socket.
pub struct SimSocket {
    stream: UnixStream,
    path: PathBuf,
}

impl SimSocket {
    /// Connects to the server at `path`.
    pub fn connect(path: impl AsRef<Path>) -> Result<SimSocket, SimLinkError> {
        let path = path.as_ref().to_path_buf();
        match UnixStream::connect(&path) {
            Ok(stream) => Ok(SimSocket { stream, path }),
            Err(source) => Err(SimLinkError::Connect { path, source }),
        }
    }

    /// The socket path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn request(&mut self, op: u8, payload: &[u8]) -> Result<Vec<u8>, SimLinkError> {
        write_message(&mut self.stream, op, payload)?;
        match read_message(&mut self.stream)? {
            None => Err(SimLinkError::Protocol("the server closed the connection".into())),
            Some((REPLY_DONE, answer)) => Ok(answer),
            Some((REPLY_FAILED, message)) => Err(SimLinkError::Server(String::from_utf8_lossy(&message).into())),
            Some((status, _)) => Err(SimLinkError::Protocol(format!("reply status {status}"))),
        }
    }
}

impl SpiTransfer for SimSocket {
    fn transfer(&mut self, tx: &[u8]) -> Result<Vec<u8>, BusError> {
        let rx = self.request(OP_TRANSFER, tx)?;
        if rx.len() != tx.len() {
            return Err(BusError::ShortAnswer { sent: tx.len(), received: rx.len() });
        }
        Ok(rx)
    }

    fn wait(&mut self, clocks: u64) -> Result<(), BusError> {
        self.request(OP_WAIT, &clocks.to_le_bytes())?;
        Ok(())
    }

    fn drive_estop(&mut self, level: bool) -> Result<bool, BusError> {
        Ok(self.request(OP_ESTOP, &[u8::from(level)])? == [1])
    }

    fn turn_wheel(&mut self, edges: i64) -> Result<bool, BusError> {
        Ok(self.request(OP_WHEEL, &edges.to_le_bytes())? == [1])
    }

    /// The server's measurement; a server that does not measure answers with a message
    /// (an error here).
    fn pin_timing(&mut self) -> Result<Option<PinTimingReport>, BusError> {
        let bytes = self.request(OP_PIN_TIMING, &[])?;
        match PinTimingReport::from_bytes(&bytes) {
            Some(report) => Ok(Some(report)),
            None => Err(SimLinkError::Protocol(format!("a pin-timing report of {} bytes", bytes.len())).into()),
        }
    }
}

/// Serves `link` to one client on `stream` until the client closes it: each transfer
/// or wait request is carried out on `link` and answered. A request `link` fails is
/// answered with its message and the connection stays up; a broken framing ends it.
pub fn serve<S: Read + Write, L: SpiTransfer + ?Sized>(stream: &mut S, link: &mut L) -> Result<(), SimLinkError> {
    while let Some((op, payload)) = read_message(stream)? {
        let result = match op {
            OP_TRANSFER => link.transfer(&payload).map_err(|e| e.to_string()),
            OP_WAIT => match <[u8; 8]>::try_from(payload.as_slice()) {
                Ok(clocks) => link.wait(u64::from_le_bytes(clocks)).map(|()| Vec::new()).map_err(|e| e.to_string()),
                Err(_) => Err(format!("a wait of {} bytes, not 8", payload.len())),
            },
            OP_ESTOP => match payload.as_slice() {
                &[level @ (0 | 1)] => {
                    link.drive_estop(level == 1).map(|driven| vec![u8::from(driven)]).map_err(|e| e.to_string())
                }
                _ => Err(format!("an E-stop level of {payload:?}, not [0] or [1]")),
            },
            OP_WHEEL => match <[u8; 8]>::try_from(payload.as_slice()) {
                Ok(edges) => link
                    .turn_wheel(i64::from_le_bytes(edges))
                    .map(|driven| vec![u8::from(driven)])
                    .map_err(|e| e.to_string()),
                Err(_) => Err(format!("a wheel turn of {} bytes, not 8", payload.len())),
            },
            OP_PIN_TIMING => match link.pin_timing() {
                Ok(Some(report)) => Ok(report.to_bytes()),
                Ok(None) => Err("this simulated chip does not measure its step pins".to_string()),
                Err(e) => Err(e.to_string()),
            },
            other => Err(format!("unknown op {other:#04x}")),
        };
        match result {
            Ok(rx) => write_message(stream, REPLY_DONE, &rx)?,
            Err(message) => write_message(stream, REPLY_FAILED, message.as_bytes())?,
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Answers every byte inverted and counts the clocks waited.
    struct Inverter {
        clocks: u64,
    }

    impl SpiTransfer for Inverter {
        fn transfer(&mut self, tx: &[u8]) -> Result<Vec<u8>, BusError> {
            Ok(tx.iter().map(|b| !b).collect())
        }
        fn wait(&mut self, clocks: u64) -> Result<(), BusError> {
            self.clocks += clocks;
            if self.clocks > 1000 {
                return Err(BusError::StillStreaming { clocks: self.clocks });
            }
            Ok(())
        }
    }

    #[test]
    fn requests_cross_the_socket_and_failures_come_back_as_messages() {
        let dir = std::env::temp_dir().join(format!("finestep-sim-link-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("chip.sock");
        let _ = std::fs::remove_file(&path);
        let listener = std::os::unix::net::UnixListener::bind(&path).unwrap();
        let server = std::thread::spawn(move || {
            let (mut stream, _) = listener.accept().unwrap();
            let mut link = Inverter { clocks: 0 };
            serve(&mut stream, &mut link).unwrap();
            link.clocks
        });
        let mut client = SimSocket::connect(&path).unwrap();
        assert_eq!(client.transfer(&[0x00, 0x5A]).unwrap(), [0xFF, 0xA5]);
        client.wait(600).unwrap();
        let err = client.wait(600).unwrap_err().to_string();
        assert!(err.contains("still streaming after 1200 clocks"), "{err}");
        assert_eq!(client.transfer(&[1]).unwrap(), [0xFE]);
        drop(client);
        assert_eq!(server.join().unwrap(), 1200);
        let err = SimSocket::connect(dir.join("nobody.sock")).err().unwrap().to_string();
        assert!(err.starts_with(&format!("sim:{}: cannot connect", dir.join("nobody.sock").display())), "{err}");
    }
}
