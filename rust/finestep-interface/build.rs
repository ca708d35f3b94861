//! Generates `OUT_DIR/registers.rs` (the `regs` module) from `hdl/registers.toml` and
//! `OUT_DIR/interface.rs` (constants, enums, `DriveTiming`, parameter ranges) from
//! `hdl/interface.toml`, with finestep-regmap's validators and generators.

use std::path::PathBuf;

fn main() {
    let manifest_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let root = manifest_dir.join("../..");
    for input in [finestep_regmap::MAP_PATH, finestep_regmap::INTERFACE_PATH] {
        println!("cargo:rerun-if-changed={}", root.join(input).display());
    }
    println!("cargo:rerun-if-changed=build.rs");
    // A bad description is the user's input: say what is wrong and stop, without a panic trace.
    let (map, interface) = match finestep_regmap::load_interface(&root) {
        Ok(loaded) => loaded,
        Err(error) => {
            eprintln!("error: {error}");
            std::process::exit(1);
        }
    };
    let Some(out_dir) = std::env::var_os("OUT_DIR").map(PathBuf::from) else {
        eprintln!("error: OUT_DIR is not set; run this through cargo");
        std::process::exit(1);
    };
    for (name, text) in [
        ("registers.rs", finestep_regmap::rust_source::generate(&map)),
        ("interface.rs", finestep_regmap::interface_rust::generate(&interface)),
    ] {
        let path = out_dir.join(name);
        if let Err(error) = std::fs::write(&path, text) {
            eprintln!("error: cannot write {}: {error}", path.display());
            std::process::exit(1);
        }
    }
}
