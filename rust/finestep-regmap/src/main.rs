//! `finestep-regmap`: writes the Verilog headers, the C header and the Markdown
//! documentation of the register map and the interface description, and checks that
//! the committed docs are current.

use anyhow::Context;
use clap::{Parser, Subcommand};
use finestep_regmap::{
    c_header, check_docs, default_root, docs, hdl_headers, load_interface, load_map, markdown, rust_source, verilog,
};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Generators for finestep's register map (hdl/registers.toml) and interface (hdl/interface.toml).
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
    /// Write every Verilog header the RTL includes (finestep_regs.vh,
    /// finestep_interface.vh, <module>_checks.vh) into DIR
    Headers {
        /// Output directory
        dir: PathBuf,
    },
    /// Write the C header of the Verilator shims (finestep_interface.h) to OUT
    CHeader {
        /// Output file
        out: PathBuf,
    },
    /// Regenerate the committed docs (docs/registers.md, docs/interface.md) under the root
    Docs,
    /// Fail unless docs/registers.md and docs/interface.md are exactly what the map and
    /// the interface description generate
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
        Command::Headers { dir } => {
            let (map, interface) = load_interface(&root)?;
            for (name, text) in hdl_headers(&map, &interface) {
                write(&dir.join(name), text)?;
            }
            Ok(())
        }
        Command::CHeader { out } => write(&out, c_header::generate(&load_interface(&root)?.1)),
        Command::Docs => {
            let (map, interface) = load_interface(&root)?;
            for (path, text) in docs(&map, &interface) {
                write(&root.join(path), text)?;
            }
            Ok(())
        }
        Command::Check => {
            check_docs(&root)?;
            println!(
                "finestep-regmap: {} and {} are current",
                finestep_regmap::DOCS_PATH,
                finestep_regmap::INTERFACE_DOCS_PATH
            );
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
