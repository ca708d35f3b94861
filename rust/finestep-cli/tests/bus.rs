//! `--bus` end to end: a part program on a chip served by `finestep sim-chip`, the bus
//! from the machine configuration, and the errors of a missing device, a socket with
//! nothing listening and a chip answering a wrong identity.

mod common;

use common::{finestep, scratch, serve};

fn program() -> String {
    let path = scratch("square.ngc");
    std::fs::write(&path, "G21 G90 G64 P0.01 F3000\nG1 X1 Y0\nG1 X1 Y1\nG1 X0 Y0\nM2\n").unwrap();
    path.display().to_string()
}

#[test]
fn a_part_program_runs_on_a_served_chip_to_its_exact_end() {
    let server = serve("run", &["--target", "model"]);
    let bus = format!("sim:{}", server.socket.display());
    let out = scratch("out").display().to_string();
    let (ok, text) = finestep(&["run", "--bus", &bus, "--out", &out, &program()]);
    assert!(ok, "{text}");
    assert!(text.contains(&format!("streamed over SPI on {bus}")), "{text}");
    let finals: Vec<&str> = text.lines().skip_while(|l| !l.contains("steps moved")).skip(1).take(2).collect();
    assert_eq!(finals.len(), 2, "{text}");
    assert!(finals.iter().all(|l| l.ends_with(" 0 steps")), "{text}");
}

#[test]
fn a_second_run_on_the_same_chip_starts_where_the_first_ended() {
    // A served chip (or a board) keeps its positions: each run is counted from where
    // the axes stand when it starts.
    let server = serve("run-twice", &["--target", "model"]);
    let bus = format!("sim:{}", server.socket.display());
    let out = scratch("out-twice").display().to_string();
    let program = scratch("out.ngc");
    std::fs::write(&program, "G21 G90 G64 P0.01 F3000\nG1 X2 Y-1\nM2\n").unwrap();
    let program = program.display().to_string();
    for _ in 0..2 {
        let (ok, text) = finestep(&["run", "--bus", &bus, "--out", &out, &program]);
        assert!(ok, "{text}");
        let moved: Vec<&str> = text.lines().skip_while(|l| !l.contains("steps moved")).skip(1).take(2).collect();
        assert_eq!(moved.len(), 2, "{text}");
        assert!(
            moved[0].starts_with("  X") && moved[0].contains(" 2.0000 mm") && moved[0].ends_with(" 0 steps"),
            "{text}"
        );
        assert!(
            moved[1].starts_with("  Y") && moved[1].contains(" -1.0000 mm") && moved[1].ends_with(" 0 steps"),
            "{text}"
        );
    }
}

#[test]
fn the_demo_takes_the_bus_and_names_what_it_cannot_reach() {
    let socket = scratch("nobody-demo.sock").display().to_string();
    let out = scratch("out-demo").display().to_string();
    let (ok, text) = finestep(&["demo", "--bus", &format!("sim:{socket}"), "--out", &out]);
    assert!(!ok);
    assert!(text.contains(&format!("sim:{socket}: cannot connect")), "{text}");
    let (ok, text) = finestep(&["demo", "--bus", "spidev:/dev/spidev9.9", "--out", &out]);
    assert!(!ok);
    assert!(text.contains("spidev:/dev/spidev9.9: no such device"), "{text}");
}

/// `finestep measure` on a served chip with the self-test's loopback machine on its pins
/// (encoder 0 follows axis 0, one count per step): the configuration's traverse of X,
/// its grating on channel 0; the gauge (channel 1) is unplugged and reads 0. A second
/// traverse on the same chip starts from where the first ended.
#[test]
fn measure_traverses_a_served_chip_with_the_configured_channels() {
    let server = serve("measure", &["--target", "model", "--plant"]);
    let config = scratch("measure.toml");
    let measure = "[measure]\naxis = \"X\"\nlength_mm = 2.0\nfeed_mm_s = 20.0\naxis_channel = 0\n\
        axis_counts_per_mm = 800.0\ngauge_channel = 1\ngauge_um_per_count = 0.5\n";
    std::fs::write(&config, format!("bus = \"sim:{}\"\n{measure}", server.socket.display())).unwrap();
    let config = config.display().to_string();
    for pass in 0..2 {
        let out = scratch(&format!("profile-{pass}.csv"));
        let (ok, text) = finestep(&["measure", "--config", &config, "--out", &out.display().to_string()]);
        assert!(ok, "{text}");
        let profile = std::fs::read_to_string(&out).unwrap();
        let rows: Vec<Vec<f64>> = profile
            .lines()
            .filter(|l| !l.starts_with('#') && !l.starts_with("z_mm"))
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect();
        // The traverse takes about 120 periods (0.1 s at 20 mm/s, the ramps at 98 % of
        // X's 1000 mm/s^2; 140 while a line took half of it): most of them latched.
        assert!(rows.len() > 70, "{text}");
        // The grating is the axis's steps: Z (the traverse axis) equals the command, in
        // whole counts of 1.25 um, rising over (0, 2) mm; the gauge reads 0.
        assert!(rows.windows(2).all(|w| w[1][0] > w[0][0]), "{profile}");
        assert!(rows.iter().all(|r| r[0] > 0.0 && r[0] < 2.0 && r[1] == 0.0 && r[0] == r[2]), "{profile}");
        assert!(rows.iter().all(|r| (r[0] / 0.00125 - (r[0] / 0.00125).round()).abs() < 1e-6), "{profile}");
        assert!(rows.last().unwrap()[0] > 1.99, "{profile}");
    }
    // A channel the chip does not have, and a chip with nothing on its encoder pins.
    let bad = scratch("measure-bad.toml");
    std::fs::write(&bad, measure.replace("axis_channel = 0", "axis_channel = 7")).unwrap();
    let bad = bad.display().to_string();
    let bus = format!("sim:{}", server.socket.display());
    let (ok, text) = finestep(&["measure", "--config", &bad, "--bus", &bus]);
    assert!(!ok);
    assert!(
        text.contains("measure.axis_channel: channel 7, but the chip has 4 encoder channels (CAPS.N_ENC)"),
        "{text}"
    );
    let (ok, text) =
        finestep(&["measure", "--config", &config, "--bus", "model", "--out", &scratch("p.csv").display().to_string()]);
    assert!(!ok);
    assert!(text.contains("the X grating (channel 0) did not move over the traverse"), "{text}");
}

#[test]
fn the_configuration_names_the_bus_and_the_command_line_overrides_it() {
    let config = scratch("machine.toml");
    let socket = scratch("nobody-config.sock");
    std::fs::write(&config, format!("bus = \"sim:{}\"\n", socket.display())).unwrap();
    let config = config.display().to_string();
    let (ok, text) = finestep(&["run", "--config", &config, &program()]);
    assert!(!ok);
    assert!(text.contains(&format!("sim:{}: cannot connect", socket.display())), "{text}");
    let out = scratch("out-model").display().to_string();
    let (ok, text) = finestep(&["run", "--config", &config, "--bus", "model", "--out", &out, &program()]);
    assert!(ok, "{text}");
    std::fs::write(&config, "bus = \"usb\"\n").unwrap();
    let (ok, text) = finestep(&["run", "--config", &config, &program()]);
    assert!(!ok);
    assert!(text.contains(&format!("{config}: bus: unknown bus `usb`")), "{text}");
}

#[test]
fn a_missing_device_a_dead_socket_and_a_wrong_identity_are_named() {
    let (ok, text) = finestep(&["run", "--bus", "spidev:/dev/spidev9.9", &program()]);
    assert!(!ok);
    assert!(text.contains("spidev:/dev/spidev9.9: no such device"), "{text}");
    let (ok, text) = finestep(&["run", "--bus", "spidev:/dev/spidev9.9@25000000", &program()]);
    assert!(!ok);
    assert!(text.contains("SCK 25000000 Hz is over the core's limit of 6250000 Hz"), "{text}");
    let socket = scratch("nobody.sock").display().to_string();
    let (ok, text) = finestep(&["run", "--bus", &format!("sim:{socket}"), &program()]);
    assert!(!ok);
    assert!(text.contains(&format!("sim:{socket}: cannot connect")), "{text}");
    let server = serve("wrong-id", &["--target", "model", "--fault", "wrong-identity"]);
    let bus = format!("sim:{}", server.socket.display());
    let (ok, text) = finestep(&["run", "--bus", &bus, &program()]);
    assert!(!ok);
    assert!(text.contains(&format!("{bus}: the chip's identity")), "{text}");
    assert!(text.contains("not a finestep core: ID reads 0xdeadbeef"), "{text}");
}

#[test]
fn the_bench_streams_on_a_served_chip() {
    let server = serve("bench", &["--target", "model"]);
    let bus = format!("sim:{}", server.socket.display());
    let (ok, text) = finestep(&["bench", "--bus", &bus]);
    assert!(ok, "{text}");
    assert!(text.contains(&format!("streamed over SPI on {bus}")), "{text}");
}
