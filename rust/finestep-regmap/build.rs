//! Generates `OUT_DIR/registers.rs`, the library's `regs` module, from
//! `hdl/registers.toml`. The parser and the generator are the library's own source
//! files, compiled here too, so the build and the `finestep-regmap` tool cannot disagree.

use std::path::PathBuf;

// The build script uses only part of each module's API.
#[allow(dead_code)]
#[path = "src/spec.rs"]
mod spec;

#[allow(dead_code)]
#[path = "src/rust_source.rs"]
mod rust_source;

fn main() {
    let manifest_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let map_path = manifest_dir.join("../../hdl/registers.toml");
    for input in ["build.rs", "src/spec.rs", "src/rust_source.rs"] {
        println!("cargo:rerun-if-changed={input}");
    }
    println!("cargo:rerun-if-changed={}", map_path.display());

    // A bad map is the user's input: say what is wrong and stop, without a panic trace.
    let map = match spec::load(&map_path) {
        Ok(map) => map,
        Err(error) => {
            eprintln!("error: {error}");
            std::process::exit(1);
        }
    };
    let out_dir = match std::env::var_os("OUT_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => {
            eprintln!("error: OUT_DIR is not set; run this through cargo");
            std::process::exit(1);
        }
    };
    let out_path = out_dir.join("registers.rs");
    if let Err(error) = std::fs::write(&out_path, rust_source::generate(&map)) {
        eprintln!("error: cannot write {}: {error}", out_path.display());
        std::process::exit(1);
    }
}
