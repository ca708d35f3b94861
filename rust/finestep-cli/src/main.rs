//! `finestep`: run the seed-000 demo move or a part program in lockstep co-simulation,
//! or measure speed.

mod bench;
mod bench_top;
mod bus;
mod config_file;
mod conformance;
mod demo;
mod demo_feedback;
mod demo_gantry;
mod gantry_figure;
mod machine_setup;
mod parameter_file;
mod plot;
mod roller;
mod run;
mod selftest;
mod sim_chip;
mod view;

use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::Instant;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "finestep", version, about = "finestep CNC motion core: co-simulation demo and benchmarks")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Seed 000's move (X/Z/C along a line, trapezoidal feed) streamed over SPI into the
    /// Verilated chip in lockstep with the reference model; prints the final positions and
    /// writes a waveform and a plot.
    Demo {
        /// Where the waveform and the plot go.
        #[arg(long, default_value = "target/demo")]
        out: PathBuf,
        /// Parts 1 and 2 on this chip: lockstep (default, every part), model,
        /// spidev:/dev/spidevB.C[@SCK_HZ] or sim:SOCKET.
        #[arg(long)]
        bus: Option<bus::BusTarget>,
    },
    /// Run a G-code part program: plan it (look-ahead, G64 blending, trapezoid or S-curve
    /// feed), check the periods independently, plot them, and stream them into the
    /// co-simulated core (G41/G42 cutter compensation is applied by the planner).
    Run {
        /// The part program.
        file: PathBuf,
        /// Use the reference model's fast path alone (no RTL), for long programs.
        #[arg(long)]
        fast: bool,
        /// The chip: lockstep (default), model, spidev:/dev/spidevB.C[@SCK_HZ] or
        /// sim:SOCKET; overrides the configuration's `bus`.
        #[arg(long)]
        bus: Option<bus::BusTarget>,
        /// Machine configuration (TOML); the built-in machine when absent.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Override the configuration's feed profile.
        #[arg(long, value_parser = ["trapezoid", "s-curve"])]
        profile: Option<String>,
        /// Where the plots go.
        #[arg(long, default_value = "target/run")]
        out: PathBuf,
        /// Serve the 3-D view (programmed and executed path, live position, progress,
        /// FIFO) on 127.0.0.1 during the run and after it, until Ctrl-C.
        #[arg(long)]
        view: bool,
        /// The view's port (0: a free one, printed).
        #[arg(long, default_value_t = 8020, requires = "view")]
        port: u16,
        /// With --fast: run at this many times real time, so the view can follow.
        #[arg(long, requires = "view")]
        pace: Option<f64>,
    },
    /// The 3-D view of a part program in the browser: the programmed path and the path of
    /// its period records, coloured by feed, with a time scrubber; served on 127.0.0.1
    /// until Ctrl-C.
    View {
        /// The part program.
        file: PathBuf,
        /// Machine configuration (TOML); the built-in machine when absent.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Override the configuration's feed profile.
        #[arg(long, value_parser = ["trapezoid", "s-curve"])]
        profile: Option<String>,
        /// The port (0: a free one, printed).
        #[arg(long, default_value_t = 8020)]
        port: u16,
        /// The page's directory (default: FINESTEP_WEB, else the checkout's web/).
        #[arg(long)]
        web: Option<PathBuf>,
    },
    /// Print finestep's canonical events for a part program (positions in the machine
    /// frame in mm), the form `conformance` compares with LinuxCNC's rs274.
    GcodeCanon {
        /// The part program.
        file: PathBuf,
        /// A LinuxCNC tool table (lengths in inches, as rs274 reads it), for G43.
        #[arg(long)]
        tool_table: Option<PathBuf>,
        /// A LinuxCNC parameter file (lengths in inches), read before the program and
        /// written back after it, as `rs274 -v FILE` does.
        #[arg(long)]
        var: Option<PathBuf>,
    },
    /// Compare finestep's interpretation with rs274's outputs listed in MANIFEST (lines
    /// `exit-status<TAB>program.ngc<TAB>rs274-output`, as scripts/conformance.sh writes).
    Conformance {
        /// The manifest.
        manifest: PathBuf,
        /// Where report.txt and diffs/ go.
        #[arg(long, default_value = "build/conformance")]
        out: PathBuf,
        /// The tool table rs274 was given (lengths in inches), for G43.
        #[arg(long)]
        tool_table: Option<PathBuf>,
    },
    /// One case of `bench --host-only`'s memory figures: plans FILE through the record
    /// stream, the program read as it is planned (or parsed whole first with `--whole`),
    /// prints `first` at the first record, then periods, seconds from the process's start
    /// to the first record, seconds in all, the peak RSS in kB and the most path elements
    /// kept at once.
    #[command(hide = true)]
    PlanMemory {
        /// The part program.
        file: PathBuf,
        /// Parse the program whole before planning (`plan_stream`), as before the
        /// parser streamed.
        #[arg(long)]
        whole: bool,
    },
    /// Lockstep and fast-path throughput figures.
    Bench {
        /// Simulated clock cycles per measurement.
        #[arg(long, default_value_t = 20_000_000)]
        cycles: u64,
        /// Only the host side: parse, plan and interpolate.
        #[arg(long)]
        host_only: bool,
        /// Only the simulation figures (core and chip level), without the host side.
        #[arg(long, conflicts_with = "host_only")]
        sim_only: bool,
        /// Only the chip-level move, streamed on this bus (lockstep, model,
        /// spidev:/dev/spidevB.C[@SCK_HZ], sim:SOCKET).
        #[arg(long)]
        bus: Option<bus::BusTarget>,
        /// Only the gantry figure (seed 001's result: the slave's error forward vs
        /// synchronised), printed and plotted to build/figures/gantry-sync-error.png.
        #[arg(long, conflicts_with_all = ["host_only", "sim_only", "bus"])]
        gantry_only: bool,
    },
    /// The bring-up pass/fail table: identity, registers, CRC refusal, FIFO, watchdog,
    /// E-stop, a move counted back on an encoder. Exits non-zero on any failure.
    Selftest {
        /// The chip: lockstep (default, with the loopback machine on its pins), model,
        /// spidev:/dev/spidevB.C[@SCK_HZ] or sim:SOCKET.
        #[arg(long)]
        bus: Option<bus::BusTarget>,
        /// Axis 0's step/dir pins are wired to encoder channel 0 (x4, one count per
        /// step): on a board, or a `sim-chip --plant`; always so on lockstep and model.
        #[arg(long)]
        loopback: bool,
    },
    /// A measuring traverse over the simulated roller (seed 000): the Z grating and the
    /// gauge latched on one clock at every period boundary; writes the profile file.
    Measure {
        /// The profile file.
        #[arg(long, default_value = "target/roller/profile.csv")]
        out: PathBuf,
        /// The chip (lockstep, model, spidev:/dev/spidevB.C[@SCK_HZ], sim:SOCKET), with the
        /// configuration's [measure] traverse; without a bus, the simulated roller.
        #[arg(long)]
        bus: Option<bus::BusTarget>,
        /// The machine configuration (TOML): axes, drive timing, [measure], bus.
        #[arg(long)]
        config: Option<PathBuf>,
    },
    /// The demo's part 4 alone: measure the roller, compensate, grind, measure again.
    #[command(hide = true)]
    RollerDemo {
        /// Where the profiles, the program and the plot go.
        #[arg(long, default_value = "target/demo")]
        out: PathBuf,
    },
    /// The demo's part 6 alone: the gantry card at the chip's pins (forward, synchronised,
    /// the alarm).
    #[command(hide = true)]
    GantryDemo {
        /// Where the plot goes.
        #[arg(long, default_value = "target/demo")]
        out: PathBuf,
    },
    /// A compensated X(Z) grinding program from a measured profile and a target.
    Compensate {
        /// The measured profile (`finestep measure`).
        profile: PathBuf,
        /// The target profile (CSV with z_mm,x_mm); a cylinder at --target-x without one.
        #[arg(long)]
        target: Option<PathBuf>,
        /// The target cylinder's X, mm.
        #[arg(long, default_value_t = -0.02, allow_hyphen_values = true)]
        target_x: f64,
        /// The noise filter's window, mm.
        #[arg(long, default_value_t = 1.5)]
        window: f64,
        /// Largest distance of the program's path from the compensated curve, mm.
        #[arg(long, default_value_t = 0.0002)]
        tolerance: f64,
        /// Where the program goes (stdout without).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Machine configuration files, crash-safe: `save` checks a configuration and writes
    /// it atomically with a checksum, keeping the previous good copy (FILE.bak); `check`
    /// says which copy loads and what is wrong with the others.
    Config {
        #[command(subcommand)]
        action: ConfigAction,
    },
    /// Serve the simulated chip on a Unix socket at the byte level of the SPI link (the
    /// framing of finestep_host::sim_link), for host tools on `--bus sim:SOCKET`.
    SimChip {
        /// The socket path (a stale socket there is replaced).
        socket: PathBuf,
        /// What simulates the chip.
        #[arg(long, value_enum, default_value = "lockstep")]
        target: sim_chip::Target,
        /// Put the self-test's loopback machine on the pins: drives on every axis, encoder
        /// channel 0 on axis 0 at one count per step.
        #[arg(long)]
        plant: bool,
        /// Put the closed-loop machine on the pins instead (`PlantConfig::lagging`): a
        /// drive on every axis lagging its step pins with this time constant in core
        /// clocks, and a linear grating on each axis an encoder channel has.
        #[arg(long, conflicts_with = "plant")]
        lag_clocks: Option<u64>,
        /// The gratings' counts per step with `--lag-clocks`.
        #[arg(long, default_value_t = 1, requires = "lag_clocks")]
        counts_per_step: u32,
        /// Inject a fault (repeatable), for tests that must notice it.
        #[arg(long, value_enum)]
        fault: Vec<sim_chip::Fault>,
        /// Exit when the first client disconnects.
        #[arg(long)]
        once: bool,
    },
}

#[derive(Subcommand)]
enum ConfigAction {
    /// Check SOURCE (TOML) and save it to FILE crash-safe.
    Save {
        /// The configuration to save.
        source: PathBuf,
        /// Where it goes (its last good copy is FILE.bak).
        file: PathBuf,
    },
    /// Load FILE as `run --config` does and report.
    Check {
        /// The configuration file.
        file: PathBuf,
    },
}

/// When `main` started: the figures of latency from the process's start.
pub(crate) static PROCESS_START: OnceLock<Instant> = OnceLock::new();

fn main() -> anyhow::Result<()> {
    PROCESS_START.get_or_init(Instant::now);
    match Cli::parse().command {
        Command::Demo { out, bus } => demo::run(&out, bus),
        Command::Run { file, fast, bus, config, profile, out, view, port, pace } => {
            let view = view.then_some(run::ViewOptions { port, pace, web: None });
            run::run(&file, fast, bus, config.as_deref(), profile.as_deref(), &out, view.as_ref())
        }
        Command::View { file, config, profile, port, web } => {
            view::view(&file, config.as_deref(), profile.as_deref(), port, web.as_deref())
        }
        Command::Bench { cycles, host_only, sim_only, bus, gantry_only } => {
            let gantry_png = PathBuf::from("build/figures/gantry-sync-error.png");
            if gantry_only {
                gantry_figure::print_figure(Some(gantry_png.as_path()))
            } else if let Some(target) = bus {
                bench_top::on_bus(&target, 200)
            } else if host_only {
                bench::front_end()
            } else {
                bench::run(cycles)?;
                if !sim_only {
                    bench::front_end()?;
                }
                bench_top::run(200)?;
                gantry_figure::print_figure(Some(gantry_png.as_path()))
            }
        }
        Command::PlanMemory { file, whole } => bench::plan_memory(&file, whole),
        Command::GcodeCanon { file, tool_table, var } => {
            conformance::canon(&file, tool_table.as_deref(), var.as_deref())
        }
        Command::Conformance { manifest, out, tool_table } => conformance::run(&manifest, &out, tool_table.as_deref()),
        Command::SimChip { socket, target, plant, lag_clocks, counts_per_step, fault, once } => {
            let machine = match lag_clocks {
                Some(tau) => sim_chip::Machine::Lagging { tau, counts_per_step },
                None if plant => sim_chip::Machine::Loopback,
                None => sim_chip::Machine::None,
            };
            sim_chip::run(&socket, target, machine, &fault, once)
        }
        Command::Selftest { bus, loopback } => selftest::run(bus, loopback),
        Command::Measure { out, bus, config } => {
            if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir)?;
            }
            roller::measure(&out, bus, config.as_deref())
        }
        Command::RollerDemo { out } => {
            std::fs::create_dir_all(&out)?;
            roller::demo(&out)
        }
        Command::GantryDemo { out } => {
            std::fs::create_dir_all(&out)?;
            demo_gantry::run(&out)
        }
        Command::Compensate { profile, target, target_x, window, tolerance, out } => {
            roller::compensate_file(&profile, target.as_deref(), target_x, window, tolerance, out.as_deref())
        }
        Command::Config { action: ConfigAction::Save { source, file } } => config_file::save(&source, &file),
        Command::Config { action: ConfigAction::Check { file } } => config_file::check(&file),
    }
}
