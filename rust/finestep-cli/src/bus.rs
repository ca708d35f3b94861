//! The host link every `finestep` tool talks over, chosen in one place: `--bus`, else
//! the machine configuration's `bus`, else the Verilated chip in lockstep with the model.
//! Every target is the host driver's [`SpiBus`] over one [`SpiTransfer`], so a tool runs
//! the same code on a board as in simulation:
//!
//! - `lockstep`: the Verilated RTL and the reference model at their pins, compared every
//!   clock, behind the driver's pin-level SPI master;
//! - `model`: the reference model alone at its pins;
//! - `spidev:/dev/spidevB.C[@SCK_HZ]`: a board (SCK 1 MHz unless given), the SCK checked
//!   against the core clock before the device is opened;
//! - `sim:SOCKET`: a chip served by `finestep sim-chip SOCKET`.
//!
//! Opening checks the identity, the map version and CAPS; a failure names the target.

use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

use anyhow::{bail, Context};
use finestep_cosim::{rtl_top_params, ModelPins, PinMonitor, PlantLoop, TopLockstep};
use finestep_host::spi::check_sck;
use finestep_host::{Machine, PinHost, PinTarget, PinTiming, SpiBus, SpiTransfer};
use finestep_model::top::Top;
use finestep_plant::{ChannelConfig, CountsPerStep, DriveConfig, EncoderConfig, Plant, PlantConfig};

/// SCK on spidev when the target does not give one.
pub const DEFAULT_SCK_HZ: u32 = 1_000_000;

/// Where a tool's chip is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BusTarget {
    /// The Verilated chip in lockstep with the model (the default).
    Lockstep,
    /// The reference model alone at its pins.
    Model,
    /// A board on Linux spidev.
    Spidev {
        /// `/dev/spidevB.C`.
        path: PathBuf,
        /// SCK, Hz.
        sck_hz: u32,
    },
    /// A chip served by `finestep sim-chip` on this Unix socket.
    Sim(PathBuf),
}

impl FromStr for BusTarget {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        match text {
            "lockstep" => return Ok(BusTarget::Lockstep),
            "model" => return Ok(BusTarget::Model),
            _ => {}
        }
        if let Some(rest) = text.strip_prefix("spidev:") {
            let (path, sck_hz) = match rest.rsplit_once('@') {
                Some((path, sck)) => {
                    let sck_hz = sck.parse().map_err(|_| format!("{text}: SCK `{sck}` is not a frequency in Hz"))?;
                    (path, sck_hz)
                }
                None => (rest, DEFAULT_SCK_HZ),
            };
            if path.is_empty() {
                return Err(format!("{text}: no device path (spidev:/dev/spidevB.C[@SCK_HZ])"));
            }
            return Ok(BusTarget::Spidev { path: path.into(), sck_hz });
        }
        if let Some(socket) = text.strip_prefix("sim:") {
            if socket.is_empty() {
                return Err(format!("{text}: no socket path (sim:SOCKET)"));
            }
            return Ok(BusTarget::Sim(socket.into()));
        }
        Err(format!("unknown bus `{text}`: lockstep, model, spidev:/dev/spidevB.C[@SCK_HZ] or sim:SOCKET"))
    }
}

impl fmt::Display for BusTarget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BusTarget::Lockstep => write!(f, "lockstep"),
            BusTarget::Model => write!(f, "model"),
            BusTarget::Spidev { path, sck_hz } => write!(f, "spidev:{}@{sck_hz}", path.display()),
            BusTarget::Sim(socket) => write!(f, "sim:{}", socket.display()),
        }
    }
}

impl BusTarget {
    /// The one resolution of the bus: the command line's, else the configuration's
    /// (`bus = ...`, named `file` in errors), else [`BusTarget::Lockstep`].
    pub fn choose(cli: Option<BusTarget>, config: Option<&str>, file: &str) -> anyhow::Result<BusTarget> {
        match (cli, config) {
            (Some(target), _) => Ok(target),
            (None, Some(text)) => text.parse().map_err(|e: String| anyhow::anyhow!("{file}: bus: {e}")),
            (None, None) => Ok(BusTarget::Lockstep),
        }
    }

    /// Whether the chip is the Verilated RTL checked against the model every clock.
    pub fn is_lockstep(&self) -> bool {
        *self == BusTarget::Lockstep
    }
}

/// A chip behind the host driver on whichever link.
pub type Link = Box<dyn SpiTransfer>;

/// A connected chip on a [`Link`].
pub type BusMachine = Machine<SpiBus<Link>>;

/// Resets a simulated chip at its pins and puts the driver's SPI master on it.
pub fn pin_link<T: PinTarget + 'static>(target: T) -> anyhow::Result<Link> {
    let mut host = PinHost::new(target, PinTiming::default());
    host.reset(4)?;
    host.idle(8)?;
    Ok(Box::new(host))
}

#[cfg(target_os = "linux")]
fn spidev_link(path: &std::path::Path, sck_hz: u32, core_clock_hz: u32) -> anyhow::Result<Link> {
    let name = format!("spidev:{}", path.display());
    check_sck(sck_hz, core_clock_hz).with_context(|| format!("{name}: nothing sent"))?;
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            bail!("{name}: no such device (SPI not enabled, or another bus/chip-select number)")
        }
        Err(e) => bail!("{name}: {e}"),
        Ok(_) => {}
    }
    let text = path.to_str().with_context(|| format!("{name}: not a UTF-8 path"))?;
    let spi = finestep_host::spidev::Spidev::open(text, sck_hz, core_clock_hz)
        .with_context(|| format!("{name}: cannot open the device at SCK {sck_hz} Hz"))?;
    Ok(Box::new(spi))
}

/// The machine on a simulated chip's pins for the self-test's loopback: a drive on
/// every axis (following the step pins exactly) and on encoder channel 0 a grating on
/// axis 0 with one count per step; `dead_encoder` leaves the channel unplugged.
pub fn loopback_plant(n_axes: usize, dead_encoder: bool) -> anyhow::Result<Plant> {
    let channels = if dead_encoder {
        Vec::new()
    } else {
        vec![ChannelConfig { axis: 0, encoder: EncoderConfig::linear_grating(CountsPerStep::integer(1)?, None) }]
    };
    let config = PlantConfig { drives: vec![DriveConfig::default(); n_axes], channels, probe: None, hand_wheel: None };
    Ok(Plant::new(config, 0x5E1F)?)
}

/// A simulated chip (lockstep or the model alone), with `plant` on its pins when given.
pub fn sim_link(lockstep: bool, name: &str, plant: Option<Plant>) -> anyhow::Result<Link> {
    match (lockstep, plant) {
        (true, None) => pin_link(TopLockstep::new(name)),
        (true, Some(plant)) => pin_link(PlantLoop::new(TopLockstep::new(name), plant)),
        (false, None) => pin_link(ModelPins(Top::new(rtl_top_params()))),
        (false, Some(plant)) => pin_link(PlantLoop::new(ModelPins(Top::new(rtl_top_params())), plant)),
    }
}

/// [`sim_link`] with the step pins' drive timing measured every clock ([`PinMonitor`]:
/// the Verilated RTL's pins in lockstep, the per-clock model's alone), reported by the
/// link's [`SpiTransfer::pin_timing`].
pub fn measured_sim_link(lockstep: bool, name: &str, plant: Option<Plant>) -> anyhow::Result<Link> {
    match (lockstep, plant) {
        (true, None) => pin_link(PinMonitor::new(TopLockstep::new(name))),
        (true, Some(plant)) => pin_link(PlantLoop::new(PinMonitor::new(TopLockstep::new(name)), plant)),
        (false, None) => pin_link(PinMonitor::new(ModelPins(Top::new(rtl_top_params())))),
        (false, Some(plant)) => pin_link(PlantLoop::new(PinMonitor::new(ModelPins(Top::new(rtl_top_params()))), plant)),
    }
}

/// Opens `target` (a simulated chip's failure waveform is named `name`) and connects:
/// identity, map version, CAPS and CLOCK_HZ checked. `core_clock_hz` is the clock the
/// SCK of a spidev target is checked against before anything is sent (the
/// configuration's, or the default build's); it is checked again against CLOCK_HZ.
pub fn open(target: &BusTarget, name: &str, core_clock_hz: u32) -> anyhow::Result<BusMachine> {
    open_with(target, name, core_clock_hz, None)
}

/// [`open`] with `plant` on the pins of a simulated chip (`lockstep`, `model`).
pub fn open_with(
    target: &BusTarget,
    name: &str,
    core_clock_hz: u32,
    plant: Option<Plant>,
) -> anyhow::Result<BusMachine> {
    let link: Link = match target {
        BusTarget::Lockstep => sim_link(true, name, plant)?,
        BusTarget::Model => sim_link(false, name, plant)?,
        #[cfg(target_os = "linux")]
        BusTarget::Spidev { path, sck_hz } => spidev_link(path, *sck_hz, core_clock_hz)?,
        #[cfg(not(target_os = "linux"))]
        BusTarget::Spidev { .. } => bail!("{target}: spidev exists on Linux only"),
        BusTarget::Sim(socket) => Box::new(finestep_host::sim_link::SimSocket::connect(socket)?),
    };
    let mut machine = Machine::connect(SpiBus::new(link, 1))
        .with_context(|| format!("{target}: the chip's identity (ID, VERSION, CAPS, CLOCK_HZ)"))?;
    let n_axes = machine.caps().n_axes;
    machine.bus().set_n_axes(n_axes);
    if let BusTarget::Spidev { sck_hz, .. } = target {
        check_sck(*sck_hz, machine.caps().clock_hz).with_context(|| format!("{target}: the chip reports CLOCK_HZ"))?;
    }
    Ok(machine)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_parse_and_print_back() {
        for text in ["lockstep", "model", "spidev:/dev/spidev0.1@2000000", "sim:/tmp/chip.sock"] {
            assert_eq!(text.parse::<BusTarget>().unwrap().to_string(), text);
        }
        let spi = "spidev:/dev/spidev0.0".parse::<BusTarget>().unwrap();
        assert_eq!(spi, BusTarget::Spidev { path: "/dev/spidev0.0".into(), sck_hz: DEFAULT_SCK_HZ });
        assert!("spidev:/dev/spidev0.0@fast".parse::<BusTarget>().unwrap_err().contains("not a frequency"));
        assert!("usb".parse::<BusTarget>().unwrap_err().starts_with("unknown bus `usb`"));
        let chosen = BusTarget::choose(None, Some("model"), "m.toml").unwrap();
        assert_eq!(chosen, BusTarget::Model);
        assert_eq!(BusTarget::choose(Some(BusTarget::Lockstep), Some("model"), "m.toml").unwrap(), BusTarget::Lockstep);
        let err = BusTarget::choose(None, Some("sim:"), "m.toml").unwrap_err().to_string();
        assert_eq!(err, "m.toml: bus: sim:: no socket path (sim:SOCKET)");
    }

    #[test]
    fn a_fast_sck_is_refused_before_the_device_is_looked_at() {
        let target: BusTarget = "spidev:/nonexistent/spidev9.9@50000000".parse().unwrap();
        let err = format!("{:#}", open(&target, "t", 50_000_000).err().unwrap());
        assert!(err.starts_with("spidev:/nonexistent/spidev9.9: nothing sent: SCK 50000000 Hz is over"), "{err}");
        let target: BusTarget = "spidev:/nonexistent/spidev9.9".parse().unwrap();
        let err = format!("{:#}", open(&target, "t", 50_000_000).err().unwrap());
        assert!(err.starts_with("spidev:/nonexistent/spidev9.9: no such device"), "{err}");
    }
}
