//! `make flash BOARD=...` (scripts/flash.sh): with no cable (here: DRY_RUN=1) it prints
//! the openFPGALoader command for each open-flow board and exits 0; an unknown board or
//! mode is refused.

use std::path::PathBuf;
use std::process::Command;

fn flash(args: &[&str]) -> (bool, String) {
    let script = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scripts/flash.sh"));
    let output = Command::new("bash").arg(script).args(args).env("DRY_RUN", "1").output().expect("run flash.sh");
    let text = String::from_utf8_lossy(&output.stdout).to_string() + &String::from_utf8_lossy(&output.stderr);
    (output.status.success(), text)
}

#[test]
fn the_dry_run_prints_the_command_of_each_board() {
    let boards = [
        ("colorlight-5a75b", "sram", "openFPGALoader -c ft2232 -m build/bitstream/ecp5/colorlight_5a75b.bit"),
        ("colorlight-5a75b", "flash", "openFPGALoader -c ft2232 -f build/bitstream/ecp5/colorlight_5a75b.bit"),
        ("ice40-hx8k", "sram", "openFPGALoader -b ice40_generic -m build/bitstream/ice40-hx8k/ice40_hx8k_breakout.bin"),
        ("icebreaker", "flash", "openFPGALoader -b ice40_generic -f build/bitstream/ice40-up5k/icebreaker.bin"),
    ];
    for (board, mode, command) in boards {
        let (ok, text) = flash(&[board, mode]);
        assert!(ok, "{text}");
        assert!(text.starts_with("flash: dry run (DRY_RUN=1); the command is:\n"), "{text}");
        assert!(text.contains(&format!("\n  {command}\n")), "{text}");
    }
}

#[test]
fn unknown_boards_and_modes_are_refused() {
    let (ok, text) = flash(&["de0-nano"]);
    assert!(!ok);
    assert!(text.contains("unknown board 'de0-nano'"), "{text}");
    let (ok, text) = flash(&["icebreaker", "eeprom"]);
    assert!(!ok);
    assert!(text.contains("unknown mode 'eeprom'"), "{text}");
}
