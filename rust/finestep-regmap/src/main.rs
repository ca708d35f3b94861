//! `finestep-regmap`: writes the Verilog header and the Markdown documentation of the
//! register map, and checks that the committed `docs/registers.md` is current.

use anyhow::Context;
use clap::{Parser, Subcommand};
use finestep_regmap::{check_docs, default_root, load_map, markdown, rust_source, verilog};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Generators for finestep's register map (hdl/registers.toml).
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    /// Repository root holding hdl/registers.toml and docs/registers.md
    /// [default: the repository this tool was built in]
    #[arg(long, global = true)]
    root: Option<PathBuf>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Write the Verilog header (finestep_regs.vh) to OUT
    Verilog {
        /// Output file
        out: PathBuf,
    },
    /// Write the Markdown documentation (docs/registers.md) to OUT
    Markdown {
        /// Output file
        out: PathBuf,
    },
    /// Write the Rust source of the `regs` module (as build.rs does) to OUT
    Rust {
        /// Output file
        out: PathBuf,
    },
    /// Fail unless docs/registers.md is exactly what the map generates
    Check,
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("finestep-regmap: {error:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    let root = cli.root.unwrap_or_else(default_root);
    match cli.command {
        Command::Verilog { out } => write(&out, verilog::generate(&load_map(&root)?)),
        Command::Markdown { out } => write(&out, markdown::generate(&load_map(&root)?)),
        Command::Rust { out } => write(&out, rust_source::generate(&load_map(&root)?)),
        Command::Check => {
            check_docs(&root)?;
            println!("finestep-regmap: {} is current", finestep_regmap::DOCS_PATH);
            Ok(())
        }
    }
}

/// Writes `text` to `path`, creating its directory. The text goes to a file beside it
/// first and is renamed into place, so a flow reading `path` while another regenerates
/// it (the FPGA flows run side by side) never sees it half written.
fn write(path: &Path, text: String) -> anyhow::Result<()> {
    if let Some(dir) = path.parent().filter(|dir| !dir.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let mut staging = path.as_os_str().to_owned();
    staging.push(format!(".{}.tmp", std::process::id()));
    let staging = Path::new(&staging);
    std::fs::write(staging, text).with_context(|| format!("cannot write {}", staging.display()))?;
    std::fs::rename(staging, path).with_context(|| format!("cannot rename {} to {}", staging.display(), path.display()))
}
