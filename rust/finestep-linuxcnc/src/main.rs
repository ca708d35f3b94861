//! `finestep-linuxcnc`: finestep under LinuxCNC from the same machine configuration
//! (TOML) that `finestep run` reads. `config` writes the INI and HAL of a mill on the
//! `finestep` HAL component; `check` runs the open-loop check over a recorded run (with
//! `--socket`, also the step timing the simulated chip measured at its pins)
//! (`scripts/linuxcnc_run.sh` does both around a headless LinuxCNC; docs/linuxcnc.md).

mod closed_loop;
mod config;
mod joints;
mod pin_timing;
mod watchdog;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "finestep-linuxcnc",
    version,
    about = "finestep as LinuxCNC's motion hardware: configuration and checks"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Write a LinuxCNC configuration (finestep.ini, finestep.hal, tool.tbl) for the
    /// machine configuration: a mill in open loop on the `finestep` HAL component.
    Config {
        /// Machine configuration (TOML); the built-in machine when absent.
        #[arg(long)]
        config: Option<PathBuf>,
        /// The chip the HAL component opens: sim:SOCKET or spidev:/dev/spidevB.C[@SCK_HZ].
        #[arg(long)]
        bus: String,
        /// The INI's DISPLAY program.
        #[arg(long, default_value = "axis")]
        display: String,
        /// Also write record.hal (sampled command and step count every servo period).
        #[arg(long)]
        record: bool,
        /// Where the files go.
        #[arg(long)]
        out: PathBuf,
        /// Open loop, or a closed loop through PID on the simulated closed-loop machine
        /// with finestep's or LinuxCNC's software stepgen (docs/linuxcnc.md#closed-loop).
        #[arg(long = "loop", value_enum, default_value = "open")]
        which: closed_loop::Loop,
        /// A closed loop's PID tuning over the default: KEY=VALUE,... (P, I, D, FF0, FF1,
        /// FF2, BIAS, DEADBAND, MAX_OUTPUT).
        #[arg(long)]
        pid: Option<String>,
    },
    /// Peak and RMS following error per joint over a closed loop's recording.
    Ferror {
        /// The recording (`halsampler -t` of the closed loop's record.hal).
        samples: PathBuf,
        /// The run's INI (joints, axis names, scales).
        #[arg(long)]
        ini: PathBuf,
    },
    /// The open-loop check over a recording of record.hal (`halsampler -t`): every
    /// period's step count against LinuxCNC's commanded position quantised to steps.
    Check {
        /// The recording.
        samples: PathBuf,
        /// Joints in the recording.
        #[arg(long)]
        joints: usize,
        /// The servo period (the INI's SERVO_PERIOD), ns.
        #[arg(long, default_value_t = 1_000_000.0)]
        period_ns: f64,
        /// The machine configuration (TOML) of the run: its drive timing widens the window
        /// in which a step counts as in flight at the latch by the step shaper's longest hold.
        #[arg(long)]
        config: Option<PathBuf>,
        /// The run was stopped (LinuxCNC's E-stop): fail unless the recording shows it.
        #[arg(long)]
        expect_stop: bool,
        /// The socket of the run's `finestep sim-chip`: also print the step timing it
        /// measured at the chip's pins, and fail on a violation of the drive timing.
        #[arg(long)]
        socket: Option<String>,
    },
    /// After LinuxCNC was killed: watch the simulated chip (reads only) for twice the
    /// watchdog timeout; fails unless the watchdog trips within it and no step follows
    /// the halt.
    Watchdog {
        /// The socket of `finestep sim-chip`.
        #[arg(long)]
        socket: String,
        /// `finestep.0.watchdog.timeout_ns`.
        #[arg(long, default_value_t = 5_000_000)]
        timeout_ns: u64,
    },
}

fn main() -> anyhow::Result<()> {
    match Cli::parse().command {
        Command::Config { config, bus, display, record, out, which, pid } => {
            config::write(config.as_deref(), &bus, &display, &out, record, which, pid.as_deref())
        }
        Command::Ferror { samples, ini } => {
            let text = std::fs::read_to_string(&ini).map_err(|e| anyhow::anyhow!("{}: {e}", ini.display()))?;
            let key = |section: &str, key: &str| ini_value(&text, section, key);
            let names = key("TRAJ", "COORDINATES").unwrap_or_default();
            let joints: usize = key("KINS", "JOINTS").and_then(|j| j.parse().ok()).unwrap_or(names.len());
            let scales: Vec<f64> = (0..joints)
                .map(|j| key(&format!("JOINT_{j}"), "SCALE").and_then(|s| s.parse().ok()).unwrap_or(1.0))
                .collect();
            closed_loop::ferror(&samples, joints, &names, &scales)
        }
        Command::Check { samples, joints, period_ns, config, expect_stop, socket } => {
            let open_loop = config::check(&samples, joints, period_ns, config.as_deref(), expect_stop);
            let pins = socket.as_deref().map_or(Ok(()), pin_timing::run);
            open_loop.and(pins)
        }
        Command::Watchdog { socket, timeout_ns } => watchdog::run(&socket, timeout_ns),
    }
}

/// The INI's `[section]key` (the first), trimmed.
fn ini_value(text: &str, section: &str, key: &str) -> Option<String> {
    let mut current = "";
    for line in text.lines().map(str::trim) {
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            current = name;
        } else if current == section {
            if let Some((k, v)) = line.split_once('=') {
                if k.trim() == key {
                    return Some(v.trim().to_string());
                }
            }
        }
    }
    None
}
