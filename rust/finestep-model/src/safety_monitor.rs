//! `safety_monitor`: the host watchdog and the external E-stop. Either sets a sticky
//! fault that halts the machine; the host clears a fault only once its cause is gone.
//! Out of reset the machine is halted with the E-stop taken as active.
//!
//! Specification: docs/spec/safety_monitor.md

/// Configuration and host inputs of one clock edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SafetyInputs {
    /// The watchdog runs.
    pub watchdog_enable: bool,
    /// Clocks from a kick to the watchdog fault (masked to the counter width).
    pub watchdog_timeout: u32,
    /// The E-stop pin is active high (else active low).
    pub estop_active_high: bool,
    /// Consecutive samples of the other level before the filtered E-stop changes; 0 acts as 1.
    pub estop_filter: u32,
    /// Host access that reloads the watchdog.
    pub kick: bool,
    /// Clear the faults whose causes are gone.
    pub clear_faults: bool,
    /// The E-stop pin.
    pub estop_pin: bool,
}

/// State of the safety monitor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SafetyMonitor {
    sync: [bool; 2],
    level: bool,
    count: u32,
    watchdog: u32,
    fault_estop: bool,
    fault_watchdog: bool,
    watchdog_mask: u32,
    filter_mask: u32,
}

impl SafetyMonitor {
    /// The reset state for counter widths `wd_width` and `filter_width` (the RTL's
    /// `WD_W`, `FILTER_W`) and the inputs present during reset.
    pub fn new(wd_width: u32, filter_width: u32, inputs: &SafetyInputs) -> Self {
        let mask = |w: u32| if w >= 32 { u32::MAX } else { (1 << w) - 1 };
        SafetyMonitor {
            sync: [inputs.estop_active_high; 2],
            level: inputs.estop_active_high,
            count: 0,
            watchdog: inputs.watchdog_timeout & mask(wd_width),
            fault_estop: true,
            fault_watchdog: false,
            watchdog_mask: mask(wd_width),
            filter_mask: mask(filter_width),
        }
    }

    /// The filtered E-stop is active.
    pub fn estop_active(&self, inputs: &SafetyInputs) -> bool {
        self.level == inputs.estop_active_high
    }

    /// Sticky E-stop fault.
    pub fn fault_estop(&self) -> bool {
        self.fault_estop
    }

    /// Sticky watchdog fault.
    pub fn fault_watchdog(&self) -> bool {
        self.fault_watchdog
    }

    /// Pulse output stops and enables drop.
    pub fn halt(&self) -> bool {
        self.fault_estop || self.fault_watchdog
    }

    /// One rising clock edge.
    pub fn step(&mut self, inputs: &SafetyInputs) {
        let filter = (inputs.estop_filter & self.filter_mask).max(1);
        let timeout = inputs.watchdog_timeout & self.watchdog_mask;
        let differs = self.sync[1] != self.level;
        let flips = differs && self.count + 1 >= filter;
        let estop_now = self.estop_active(inputs);
        let expired = inputs.watchdog_enable && self.watchdog == 0 && !inputs.kick;

        self.sync = [inputs.estop_pin, self.sync[0]];
        self.count = if !differs || flips { 0 } else { (self.count + 1) & self.filter_mask };
        if flips {
            self.level = !self.level;
        }
        if inputs.kick || !inputs.watchdog_enable {
            self.watchdog = timeout;
        } else if self.watchdog != 0 {
            self.watchdog -= 1;
        }
        self.fault_estop = estop_now || (self.fault_estop && !inputs.clear_faults);
        self.fault_watchdog = expired || (self.fault_watchdog && !inputs.clear_faults);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inputs() -> SafetyInputs {
        SafetyInputs {
            watchdog_enable: false,
            watchdog_timeout: 10,
            estop_active_high: false, // a normally closed E-stop loop: low is active
            estop_filter: 3,
            kick: false,
            clear_faults: false,
            estop_pin: true, // loop closed: released
        }
    }

    #[test]
    fn starts_halted_and_clears_only_after_the_estop_is_seen_released() {
        let mut inputs = inputs();
        let mut monitor = SafetyMonitor::new(24, 8, &inputs);
        assert!(monitor.halt());
        inputs.clear_faults = true;
        monitor.step(&inputs); // the filter has not yet seen the release
        assert!(monitor.fault_estop());
        for _ in 0..6 {
            monitor.step(&inputs);
        }
        assert!(!monitor.halt(), "released for 2 sync + 3 filter samples, then cleared");
    }

    #[test]
    fn a_short_glitch_is_filtered_and_a_held_estop_halts_in_time() {
        let mut inputs = inputs();
        let mut monitor = SafetyMonitor::new(24, 8, &inputs);
        inputs.clear_faults = true;
        for _ in 0..8 {
            monitor.step(&inputs);
        }
        inputs.clear_faults = false;
        // Two samples of the active level: shorter than the filter.
        inputs.estop_pin = false;
        monitor.step(&inputs);
        monitor.step(&inputs);
        inputs.estop_pin = true;
        for _ in 0..10 {
            monitor.step(&inputs);
        }
        assert!(!monitor.halt());
        // Held: halts within 3 + FILTER clocks.
        inputs.estop_pin = false;
        let mut clocks = 0;
        while !monitor.halt() {
            monitor.step(&inputs);
            clocks += 1;
        }
        assert!(clocks <= 3 + 3, "halted after {clocks} clocks");
        // Cannot be cleared while held.
        inputs.clear_faults = true;
        for _ in 0..5 {
            monitor.step(&inputs);
        }
        assert!(monitor.fault_estop());
    }

    #[test]
    fn the_watchdog_trips_without_kicks_and_not_with_them() {
        let mut inputs = SafetyInputs { watchdog_enable: true, estop_pin: false, estop_active_high: true, ..inputs() };
        let mut monitor = SafetyMonitor::new(24, 8, &inputs);
        inputs.clear_faults = true;
        inputs.kick = true;
        for _ in 0..8 {
            monitor.step(&inputs);
        }
        inputs.clear_faults = false;
        assert!(!monitor.halt());
        for cycle in 0..100 {
            inputs.kick = cycle % 10 == 0;
            monitor.step(&inputs);
        }
        assert!(!monitor.fault_watchdog(), "kicked every timeout clocks");
        inputs.kick = false;
        let mut clocks = 0;
        while !monitor.fault_watchdog() {
            monitor.step(&inputs);
            clocks += 1;
        }
        assert!(clocks <= 10 + 2, "tripped after {clocks} clocks");
    }
}
