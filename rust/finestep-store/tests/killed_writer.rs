//! A real writer process killed (SIGKILL) at random instants, over and over: every load
//! afterwards reads a whole configuration that some save wrote, never an older one than
//! the last read, never a torn or mixed one.
//!
//! The writer is this test binary itself, started with the ignored test
//! `writer_process` selected: it saves generation after generation until it is killed.
//! `FINESTEP_CASES` sets the number of kills (1000 by default), `FINESTEP_SEED` the
//! instants.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use finestep_store::{backup_path, load, save, LoadOptions, OsFs, Source};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

const CHILD_DIR: &str = "FINESTEP_STORE_WRITER_DIR";
const READY: &str = "finestep-store writer ready";

/// Generation `g`'s content: its length varies with `g`.
fn payload(g: u64) -> Vec<u8> {
    format!(
        "[machine]\ngeneration = {g}\nperiod_ms = {}.0\nnote = \"{}\"\n",
        g % 5 + 1,
        "z".repeat((g as usize * 37) % 300)
    )
    .into_bytes()
}

fn parse(bytes: &[u8]) -> Result<u64, String> {
    let text = std::str::from_utf8(bytes).map_err(|e| e.to_string())?;
    let g = text
        .lines()
        .find_map(|l| l.strip_prefix("generation = "))
        .and_then(|g| g.parse().ok())
        .ok_or("no generation line")?;
    if bytes != payload(g) {
        return Err(format!("content is not generation {g}'s"));
    }
    Ok(g)
}

fn config_path(dir: &Path) -> PathBuf {
    dir.join("machine.toml")
}

#[test]
#[ignore = "the writer process that killed_writer_never_leaves_a_wrong_configuration starts and kills"]
fn writer_process() {
    let dir = PathBuf::from(std::env::var_os(CHILD_DIR).expect("started by the kill test"));
    let path = config_path(&dir);
    let mut g = load(&mut OsFs, &path, LoadOptions::default(), parse).map_or(0, |l| l.value);
    println!("{READY}");
    loop {
        g += 1;
        let written = save(&mut OsFs, &path, &payload(g)).expect("save");
        assert_eq!(written, g);
    }
}

#[test]
fn killed_writer_never_leaves_a_wrong_configuration() {
    let seed = finestep_testkit::seed("store_killed_writer");
    let kills = finestep_testkit::cases(1000);
    eprintln!("store_killed_writer: FINESTEP_SEED={seed:#x}, {kills} kills (FINESTEP_CASES)");
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let dir = std::env::temp_dir().join(format!("finestep-store-kill-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let path = config_path(&dir);
    let exe = std::env::current_exe().unwrap();
    // Kills land anywhere in the first save or two after the writer starts: the delay
    // is drawn up to one and a half times what a save takes on this disk (its fsyncs).
    let probe = dir.join("timing.toml");
    let timer = Instant::now();
    for g in 1..=3 {
        save(&mut OsFs, &probe, &payload(g)).unwrap();
    }
    let save_us = timer.elapsed().as_micros() as u64 / 3;
    let max_delay_us = (save_us * 3 / 2).clamp(500, 15_000);
    eprintln!("store_killed_writer: a save takes {save_us} us; kill delays drawn in 0..{max_delay_us} us");
    let started = Instant::now();
    let (mut last, mut mid_save, mut fallbacks) = (0u64, 0u32, 0u32);
    for kill in 0..kills {
        let mut child = Command::new(&exe)
            .args(["writer_process", "--exact", "--ignored", "--nocapture", "--test-threads=1"])
            .env(CHILD_DIR, &dir)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let mut out = BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        while out.read_line(&mut line).unwrap() > 0 && !line.contains(READY) {
            line.clear();
        }
        assert!(line.contains(READY), "kill {kill}: the writer did not start");
        std::thread::sleep(Duration::from_micros(rng.random_range(0..max_delay_us)));
        child.kill().unwrap();
        child.wait().unwrap();
        let tmp_left = ["machine.toml.tmp", "machine.toml.bak.tmp"].iter().any(|n| dir.join(n).exists());
        mid_save += u32::from(tmp_left);
        match load(&mut OsFs, &path, LoadOptions::default(), parse) {
            Ok(loaded) => {
                assert!(loaded.value >= last, "kill {kill}: generation {} after {last}", loaded.value);
                assert_eq!(loaded.value, loaded.generation, "kill {kill}: the seal's generation");
                // A killed process loses nothing the kernel has: the file itself is whole.
                assert_eq!(loaded.source, Source::Current, "kill {kill}: {:?}", loaded.problems);
                fallbacks += u32::from(loaded.source != Source::Current);
                last = loaded.value;
            }
            Err(finestep_store::StoreError::NotFound { .. }) if last == 0 => {}
            Err(e) => panic!("kill {kill} (seed {seed:#x}): {e}"),
        }
    }
    let backup = load(&mut OsFs, &backup_path(&path), LoadOptions::default(), parse);
    eprintln!(
        "store_killed_writer: {kills} kills in {:.1} s; {last} generations written; {mid_save} kills left a \
         temporary file (killed inside a save); {fallbacks} fallbacks; last good copy: generation {:?}",
        started.elapsed().as_secs_f64(),
        backup.map(|b| b.value).ok()
    );
    assert!(last > 0, "no save completed");
    assert!(mid_save > 0, "no kill landed inside a save");
    std::fs::remove_dir_all(&dir).unwrap();
}
