//! The product path (G-code -> planner -> host driver -> board) builds on this crate,
//! never on the reference model: neither finestep-planner nor finestep-host (nor
//! finestep-gcode) may list finestep-model or finestep-rtl-sys among any of their
//! dependencies.

use std::path::Path;

const PRODUCT_PATH: [&str; 3] = ["finestep-gcode", "finestep-planner", "finestep-host"];
const VERIFICATION_SIDE: [&str; 4] = ["finestep-model", "finestep-rtl-sys", "finestep-cosim", "finestep-plant"];

/// Every dependency name in `table`'s dependency sections, target-specific ones included.
fn dependencies(table: &toml::Table) -> Vec<String> {
    let mut names = Vec::new();
    for section in ["dependencies", "dev-dependencies", "build-dependencies"] {
        if let Some(deps) = table.get(section).and_then(toml::Value::as_table) {
            names.extend(deps.keys().cloned());
        }
    }
    if let Some(targets) = table.get("target").and_then(toml::Value::as_table) {
        for target in targets.values().filter_map(toml::Value::as_table) {
            names.extend(dependencies(target));
        }
    }
    names
}

#[test]
fn the_product_path_does_not_depend_on_the_verification_side() {
    let rust = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    for krate in PRODUCT_PATH {
        let text = std::fs::read_to_string(rust.join(krate).join("Cargo.toml")).unwrap();
        let manifest: toml::Table = text.parse().unwrap();
        let deps = dependencies(&manifest);
        for forbidden in VERIFICATION_SIDE {
            assert!(!deps.iter().any(|d| d == forbidden), "{krate} depends on {forbidden}: {deps:?}");
        }
    }
    // And the two that need the contract get it from here.
    for krate in ["finestep-planner", "finestep-host"] {
        let text = std::fs::read_to_string(rust.join(krate).join("Cargo.toml")).unwrap();
        assert!(dependencies(&text.parse().unwrap()).iter().any(|d| d == "finestep-interface"), "{krate}");
    }
}
