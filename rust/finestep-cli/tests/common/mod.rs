//! What the CLI's end-to-end tests share: running `finestep`, a scratch folder, and a
//! `finestep sim-chip` server process.

// Each test binary uses only some of these.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Runs `finestep` with `args`: whether it succeeded, and its stdout and stderr.
pub fn finestep(args: &[&str]) -> (bool, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_finestep")).args(args).output().expect("run finestep");
    let text = String::from_utf8_lossy(&output.stdout).to_string() + &String::from_utf8_lossy(&output.stderr);
    (output.status.success(), text)
}

/// `name` in this test process's scratch folder.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("finestep-cli-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A `finestep sim-chip` process, killed when dropped.
pub struct Server {
    child: Child,
    /// The socket it serves.
    pub socket: PathBuf,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_file(&self.socket);
    }
}

/// Starts `finestep sim-chip` on a fresh socket named `name` with `args`, and waits
/// until it accepts connections.
pub fn serve(name: &str, args: &[&str]) -> Server {
    let socket = scratch(&format!("{name}.sock"));
    let _ = std::fs::remove_file(&socket);
    let child = Command::new(env!("CARGO_BIN_EXE_finestep"))
        .arg("sim-chip")
        .arg(&socket)
        .args(args)
        .stdout(Stdio::null())
        .spawn()
        .expect("start finestep sim-chip");
    let server = Server { child, socket };
    let started = Instant::now();
    while !server.socket.exists() {
        assert!(started.elapsed() < Duration::from_secs(60), "sim-chip never bound {}", server.socket.display());
        std::thread::sleep(Duration::from_millis(20));
    }
    server
}
