//! `finestep selftest` against the simulated chip: every check passes in process and on
//! `finestep sim-chip --plant`, and each fault the server injects (a wrong identity, a dead
//! encoder, a stuck register bit) is reported as a failure with a non-zero exit.

mod common;

use common::{finestep, serve};

fn row<'a>(text: &'a str, check: &str) -> &'a str {
    text.lines().find(|l| l.trim_start().starts_with(check)).unwrap_or_else(|| panic!("no row {check}:\n{text}"))
}

const CHECKS: [&str; 7] = [
    "identity, map, CAPS",
    "register read-back",
    "bad CRC refused",
    "FIFO threshold, underrun",
    "watchdog halt, clear",
    "E-stop input",
    "loopback move",
];

#[test]
fn every_check_passes_on_the_lockstep_chip_and_on_a_served_chip() {
    let (ok, text) = finestep(&["selftest"]);
    assert!(ok, "{text}");
    for check in CHECKS {
        assert!(row(&text, check).contains(" PASS "), "{text}");
    }
    assert!(row(&text, "loopback move").ends_with("axis 0: 200 steps, encoder 0: 200 counts"), "{text}");
    let server = serve("good", &["--plant"]);
    let (ok, served) = finestep(&["selftest", "--loopback", "--bus", &format!("sim:{}", server.socket.display())]);
    assert!(ok, "{served}");
    for check in CHECKS {
        assert_eq!(row(&served, check), row(&text, check), "{served}");
    }
}

#[test]
fn a_dead_encoder_fails_the_loopback_move() {
    let server = serve("dead-encoder", &["--fault", "dead-encoder", "--target", "model"]);
    let (ok, text) = finestep(&["selftest", "--loopback", "--bus", &format!("sim:{}", server.socket.display())]);
    assert!(!ok, "{text}");
    assert!(row(&text, "loopback move").contains("FAIL   axis 0 made 200 steps, encoder 0 counted 0"), "{text}");
    assert!(row(&text, "E-stop input").contains(" PASS "), "{text}");
    assert!(text.contains("selftest: 1 of 7 checks failed"), "{text}");
}

#[test]
fn a_wrong_identity_fails_the_first_check_naming_what_id_read() {
    let server = serve("wrong-id", &["--fault", "wrong-identity", "--target", "model"]);
    let bus = format!("sim:{}", server.socket.display());
    let (ok, text) = finestep(&["selftest", "--bus", &bus]);
    assert!(!ok, "{text}");
    let identity = row(&text, "identity, map, CAPS");
    assert!(identity.contains("FAIL"), "{text}");
    assert!(identity.contains(&format!("{bus}: ")) && identity.contains("ID reads 0xdeadbeef"), "{text}");
}

#[test]
fn a_missing_board_fails_naming_the_device() {
    let (ok, text) = finestep(&["selftest", "--bus", "spidev:/dev/spidev9.9"]);
    assert!(!ok, "{text}");
    assert!(row(&text, "identity, map, CAPS").contains("FAIL   spidev:/dev/spidev9.9: no such device"), "{text}");
}

#[test]
fn a_stuck_register_bit_fails_the_read_back() {
    let server = serve("stuck-bit", &["--fault", "stuck-bit", "--target", "model", "--plant"]);
    let (ok, text) = finestep(&["selftest", "--loopback", "--bus", &format!("sim:{}", server.socket.display())]);
    assert!(!ok, "{text}");
    assert!(row(&text, "identity, map, CAPS").contains(" PASS "), "{text}");
    assert!(row(&text, "register read-back").contains("FAIL   PERIOD_CLOCKS: wrote 0xaaaaa, read 0xaaaae"), "{text}");
}
