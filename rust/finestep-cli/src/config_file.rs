//! Machine configuration files through the crash-safe store (`finestep_store`): `run
//! --config` and `finestep config` read them sealed or hand-written, report a fallback to
//! the last good copy, and `finestep config save` writes them crash-safe.

use std::path::Path;

use anyhow::Context;
use finestep_planner::MachineConfig;
use finestep_store::{LoadOptions, Loaded, OsFs, Source};

/// The configuration at `path` ([`load`]) or, without one, the built-in machine; with the
/// name errors give it (the path, or `<built-in>`).
pub fn load_or_builtin(path: Option<&Path>) -> anyhow::Result<(MachineConfig, String)> {
    Ok(match path {
        Some(path) => (load(path)?, path.display().to_string()),
        None => (MachineConfig::default(), "<built-in>".to_string()),
    })
}

/// Loads the configuration at `path`: sealed (checked) or hand-written; a fallback to the
/// last good copy is printed with what was wrong with the file.
pub fn load(path: &Path) -> anyhow::Result<MachineConfig> {
    let loaded = load_quiet(path)?;
    if loaded.source == Source::LastGood {
        for problem in &loaded.problems {
            eprintln!("warning: {problem}");
        }
        eprintln!(
            "warning: {}: using the last good copy ({}, generation {})",
            path.display(),
            finestep_store::backup_path(path).display(),
            loaded.generation
        );
    }
    Ok(loaded.value)
}

fn load_quiet(path: &Path) -> anyhow::Result<Loaded<MachineConfig>> {
    let name = path.display().to_string();
    let parse = |bytes: &[u8]| {
        let text = std::str::from_utf8(bytes).map_err(|e| format!("not UTF-8 text: {e}"))?;
        MachineConfig::from_toml_str(text, &name).map_err(|e| e.to_string())
    };
    Ok(finestep_store::load(&mut OsFs, path, LoadOptions { accept_unsealed: true }, parse)?)
}

/// `finestep config check FILE`: which copy loads, its generation, what is wrong.
pub fn check(path: &Path) -> anyhow::Result<()> {
    let loaded = load_quiet(path)?;
    for problem in &loaded.problems {
        println!("  problem: {problem}");
    }
    let generation = match loaded.source {
        Source::Unsealed => "no seal: written by hand, not yet saved by `finestep config save`".to_string(),
        _ => format!("generation {}", loaded.generation),
    };
    println!("{}: valid machine configuration from {} ({generation})", path.display(), loaded.source);
    Ok(())
}

/// `finestep config save SOURCE FILE`: validates SOURCE and writes it to FILE
/// crash-safe, FILE's previous good content becoming its last good copy.
pub fn save(source: &Path, path: &Path) -> anyhow::Result<()> {
    let bytes = std::fs::read(source).with_context(|| format!("reading {}", source.display()))?;
    // A sealed source is saved without its seal.
    let payload = finestep_store::unseal(&bytes).map_or(&bytes[..], |(payload, _)| payload);
    let text = std::str::from_utf8(payload).with_context(|| format!("{}: not UTF-8 text", source.display()))?;
    MachineConfig::from_toml_str(text, &source.display().to_string())?;
    let generation = finestep_store::save(&mut OsFs, path, payload)?;
    println!(
        "{}: saved generation {generation} (checksummed; the previous good copy kept as {})",
        path.display(),
        finestep_store::backup_path(path).display()
    );
    Ok(())
}

/// Sets the configuration's feed profile from `--profile` (trapezoid or s-curve).
pub fn set_profile(config: &mut MachineConfig, profile: Option<&str>) {
    match profile {
        Some("trapezoid") => config.profile = finestep_planner::ProfileKind::Trapezoid,
        Some("s-curve") => config.profile = finestep_planner::ProfileKind::SCurve,
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saved_configurations_load_and_a_corrupt_one_falls_back() {
        let dir = std::env::temp_dir().join(format!("finestep-config-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (source, path) = (dir.join("in.toml"), dir.join("machine.toml"));
        std::fs::write(&source, "period_ms = 2.0\n").unwrap();
        save(&source, &path).unwrap();
        std::fs::write(&source, "period_ms = 0.5\n").unwrap();
        save(&source, &path).unwrap();
        assert_eq!(load(&path).unwrap().period_ms, 0.5);
        // A flipped digit: the checksum catches it, the last good copy answers.
        let text = std::fs::read_to_string(&path).unwrap().replacen("0.5", "0.7", 1);
        std::fs::write(&path, text).unwrap();
        let loaded = load_quiet(&path).unwrap();
        assert_eq!((loaded.value.period_ms, loaded.source, loaded.generation), (2.0, Source::LastGood, 1));
        // An invalid configuration is refused before anything is written.
        std::fs::write(&source, "period_ms = -1.0\n").unwrap();
        assert!(save(&source, &path).is_err());
        assert!(check(&path).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
