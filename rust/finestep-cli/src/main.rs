//! `finestep`: run the seed-000 demo move in lockstep co-simulation, or measure speed.

mod bench;
mod demo;
mod plot;
mod run;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "finestep", version, about = "finestep CNC motion core: co-simulation demo and benchmarks")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Seed 000's move (X/Z/C along a line, trapezoidal feed) through the Verilated RTL in
    /// lockstep with the reference model; prints counts and writes a waveform and a plot.
    Demo {
        /// Where the waveform and the plot go.
        #[arg(long, default_value = "target/demo")]
        out: PathBuf,
    },
    /// Run a G-code part program (exact stop at every block; no look-ahead or cutter
    /// compensation yet) through the planner into the co-simulated core.
    Run {
        /// The part program.
        file: PathBuf,
        /// Use the reference model's fast path alone (no RTL), for long programs.
        #[arg(long)]
        fast: bool,
    },
    /// Lockstep and fast-path throughput figures.
    Bench {
        /// Simulated clock cycles per measurement.
        #[arg(long, default_value_t = 20_000_000)]
        cycles: u64,
    },
}

fn main() -> anyhow::Result<()> {
    match Cli::parse().command {
        Command::Demo { out } => demo::run(&out),
        Command::Run { file, fast } => run::run(&file, fast),
        Command::Bench { cycles } => bench::run(cycles),
    }
}
