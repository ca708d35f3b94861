//! The register bus between its masters (`spi_frame`, `parallel_bus_slave`) and
//! `register_file`, which arbitrates and serves it: the request a master holds.
//!
//! Specification: docs/spec/register_file.md

/// A register-bus request, held by its master until granted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BusRequest {
    /// `we`: a write (else a read).
    pub write: bool,
    /// `addr[6:0]`: the word address.
    pub addr: u8,
    /// `wdata`: the word to write.
    pub wdata: u32,
}
