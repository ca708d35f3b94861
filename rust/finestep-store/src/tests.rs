//! The seal, corruption of every byte and length, and a simulated power loss at every
//! step of a save.

use super::*;
use crate::sim::SimFs;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// The content of generation `g`: lengths differ, so a torn or mixed file cannot pass
/// for another generation's.
fn payload(g: u64) -> Vec<u8> {
    format!(
        "# parameters, generation {g}\nperiod_ms = {}.0\npad = \"{}\"\n",
        g % 7 + 1,
        "x".repeat((g as usize * 13) % 41)
    )
    .into_bytes()
}

fn text(bytes: &[u8]) -> Result<String, String> {
    String::from_utf8(bytes.to_vec()).map_err(|e| e.to_string())
}

fn path() -> PathBuf {
    PathBuf::from("/machine/params.toml")
}

#[test]
fn seal_round_trips_with_and_without_a_final_newline() {
    for payload in [&b""[..], b"a", b"a\n", b"a = 1\nb = 2", b"\n\n", b"# finestep-store v1 generation=1\n"] {
        let sealed = seal(payload, 7);
        assert_eq!(unseal(&sealed), Ok((payload, 7)), "{payload:?}");
    }
    let sealed = String::from_utf8(seal(b"x = 1\n", 3)).unwrap();
    assert!(sealed.starts_with("x = 1\n# finestep-store v1 generation=3 length=6 crc32c="), "{sealed}");
    assert_eq!(unseal(b"x = 1\n"), Err(Corruption::NoSeal));
}

#[test]
fn every_flipped_byte_and_every_truncation_falls_back_to_the_last_good_copy() {
    let mut fs = SimFs::new();
    save(&mut fs, &path(), &payload(1)).unwrap();
    save(&mut fs, &path(), &payload(2)).unwrap();
    let good = fs.get(&path()).unwrap().to_vec();
    let mut cases = 0;
    let mut check = |bytes: Vec<u8>, what: String| {
        let mut fs = fs.clone();
        fs.put(&path(), &bytes);
        let loaded = load(&mut fs, &path(), LoadOptions { accept_unsealed: true }, text).unwrap();
        assert_eq!(loaded.source, Source::LastGood, "{what}");
        assert_eq!((loaded.value.into_bytes(), loaded.generation), (payload(1), 1), "{what}");
        assert_eq!(loaded.problems.len(), 1, "{what}");
        assert_eq!(loaded.problems[0].path, path());
        cases += 1;
    };
    for i in 0..good.len() {
        for bit in 0..8 {
            let mut bytes = good.clone();
            bytes[i] ^= 1 << bit;
            check(bytes, format!("byte {i} bit {bit} flipped"));
        }
    }
    for len in 0..good.len() {
        check(good[..len].to_vec(), format!("truncated to {len} bytes"));
    }
    assert_eq!(cases, good.len() * 9);
}

#[test]
fn problems_are_reported_and_no_good_copy_is_an_error() {
    let mut fs = SimFs::new();
    assert!(matches!(load(&mut fs, &path(), LoadOptions::default(), text), Err(StoreError::NotFound { .. })));
    save(&mut fs, &path(), &payload(1)).unwrap();
    // The first save leaves no last good copy: a corrupt file is an error naming both.
    let mut bytes = fs.get(&path()).unwrap().to_vec();
    bytes[3] ^= 0x20;
    fs.put(&path(), &bytes);
    let err = load(&mut fs, &path(), LoadOptions::default(), text).unwrap_err().to_string();
    assert!(err.contains("checksum") && err.contains("params.toml.bak: missing"), "{err}");
    // A save over a corrupt file keeps no copy of it, and numbers on.
    assert_eq!(save(&mut fs, &path(), &payload(2)).unwrap(), 1);
    assert_eq!(save(&mut fs, &path(), &payload(3)).unwrap(), 2);
    // The parser rejects the file: the last good copy answers, the reason is kept.
    let strict = |b: &[u8]| if b == payload(3) { Err("period_ms out of range".to_string()) } else { text(b) };
    let loaded = load(&mut fs, &path(), LoadOptions::default(), strict).unwrap();
    assert_eq!((loaded.source, loaded.generation), (Source::LastGood, 1));
    assert_eq!(loaded.problems[0].kind, Corruption::Rejected("period_ms out of range".into()));
    // Both copies bad.
    let backup = backup_path(&path());
    fs.put(&backup, b"junk");
    let err = load(&mut fs, &path(), LoadOptions::default(), strict).unwrap_err();
    assert!(matches!(&err, StoreError::NoGoodCopy { problems, .. } if problems.len() == 2), "{err}");
    // A hand-written file: accepted only when asked and when no copy says it is managed.
    let mut fs = SimFs::new();
    fs.put(&path(), b"period_ms = 1.0\n");
    assert!(load(&mut fs, &path(), LoadOptions::default(), text).is_err());
    let loaded = load(&mut fs, &path(), LoadOptions { accept_unsealed: true }, text).unwrap();
    assert_eq!((loaded.source, loaded.generation), (Source::Unsealed, 0));
    fs.put(&backup, &seal(b"period_ms = 3.0\n", 4));
    let loaded = load(&mut fs, &path(), LoadOptions { accept_unsealed: true }, text).unwrap();
    assert_eq!((loaded.source, loaded.generation, loaded.value.as_str()), (Source::LastGood, 4, "period_ms = 3.0\n"));
    assert!(matches!(
        load(&mut SimFs::new(), Path::new("/"), LoadOptions::default(), text),
        Err(StoreError::NotAFile { .. })
    ));
}

/// A power loss after every number of operations of a save, with every kind of loss
/// drawn many times: the load afterwards reads the previous generation or the new one,
/// whole, and the new one whenever the save had returned; the store keeps working.
#[test]
fn power_loss_at_every_step_of_a_save_never_reads_a_wrong_configuration() {
    let seed = finestep_testkit::seed("store_power_loss_at_every_step");
    eprintln!("store_power_loss_at_every_step: FINESTEP_SEED={seed:#x}");
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let draws = finestep_testkit::cases(64) as usize;
    let mut crashes = 0;
    for before in 0..4u64 {
        let mut base = SimFs::new();
        for g in 1..=before {
            save(&mut base, &path(), &payload(g)).unwrap();
        }
        let mut counting = base.clone();
        let start = counting.ops();
        save(&mut counting, &path(), &payload(before + 1)).unwrap();
        let steps = counting.ops() - start;
        for k in 0..=steps {
            for _ in 0..draws {
                let mut fs = base.clone();
                fs.crash_after(k);
                let saved = save(&mut fs, &path(), &payload(before + 1));
                fs.power_loss(|n| rng.random_range(0..n));
                crashes += 1;
                let what = format!("generation {} crashed after {k} of {steps} operations", before + 1);
                match load(&mut fs, &path(), LoadOptions::default(), text) {
                    Ok(loaded) => {
                        let g = loaded.generation;
                        assert!(g == before + 1 || (g == before && saved.is_err()), "{what}: read generation {g}");
                        assert_eq!(loaded.value.into_bytes(), payload(g), "{what}: generation {g}'s content");
                        assert_eq!(loaded.source, Source::Current, "{what}: the file itself is always whole");
                    }
                    Err(StoreError::NotFound { .. }) => assert!(before == 0 && saved.is_err(), "{what}: not found"),
                    Err(e) => panic!("{what}: {e}"),
                }
                // After the reboot the store saves and loads again.
                let next = save(&mut fs, &path(), b"after = true\n").unwrap();
                let loaded = load(&mut fs, &path(), LoadOptions::default(), text).unwrap();
                assert_eq!(
                    (loaded.value.as_str(), loaded.generation, loaded.source),
                    ("after = true\n", next, Source::Current)
                );
            }
        }
    }
    eprintln!("store_power_loss_at_every_step: {crashes} simulated power losses");
    assert!(crashes >= 1000);
}
