//! The gantry card's chip at its pins, RTL and model in lockstep every clock
//! ([`PanelChipLockstep`]): `finestep_top` with the panel and the gantry pair
//! ([`RtlPanelChip`]), a keypad matrix between the column and row pins
//! ([`Keypad`], its keys changed at scheduled cycles, so a test bounces them), and a
//! gantry plant ([`GantryPlant`]): two motors on the master's and the slave's step/dir
//! pins with encoders on channels 0 and 1, the slave's able to stall (lose steps) or to
//! run under a load that makes it lose some ([`SlaveLoad`]).
//! Every packed output and every panel pin is compared on every clock; the host driver
//! reaches the chip through [`PinTarget`] ([`PanelMachine`]). The card's start-up
//! ([`acknowledge_power_up`]) and its LED display read back from the pins
//! ([`read_display`]) serve the lockstep tests and `finestep demo`'s gantry part.

use std::collections::VecDeque;
use std::fmt;

use finestep_host::regs::panel_menu;
use finestep_host::{Bus, BusError, Machine, PanelMenu, PanelScan, PinHost, PinTarget, SpiBus};
use finestep_model::keypad_scan::Keypad;
use finestep_model::top::{top_pins, Top, TopInputs};
use finestep_model::TopParams;
use finestep_rtl_sys::panel_chip::panel_bits;
use finestep_rtl_sys::{top_build_of, RtlPanelChip, TopVariant};

/// The model parameters of the Verilated gantry-card chip.
pub fn panel_chip_params() -> TopParams {
    let build = top_build_of(TopVariant::Full);
    TopParams {
        n_axes: build.n_axes,
        p_width: build.p_width,
        timing_w: build.timing_width,
        fifo_depth_log2: build.fifo_depth_log2,
        n_enc: build.n_enc,
        has_mpg: build.has_mpg,
        step_shared: false,
        has_spindle: build.has_spindle,
        has_outputs: build.has_outputs,
        n_gpio: build.n_gpio,
        has_pbp: build.has_pbp,
        has_panel: true,
        has_gantry: true,
        ..TopParams::default()
    }
}

/// Two motors of one gantry axis on the step/dir pins of `master` and `slave` (one count
/// of their encoder per step, x4 quadrature on channels `enc_master`, `enc_slave`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GantryPlant {
    /// The master's axis.
    pub master: usize,
    /// The slave's axis.
    pub slave: usize,
    /// The master side's encoder channel.
    pub enc_master: usize,
    /// The slave side's encoder channel.
    pub enc_slave: usize,
    /// The motors' positions in steps (= counts).
    pub position: [i64; 2],
    /// Steps the slave motor still loses (a stall: its step pulses do not move it).
    pub stall_steps: u32,
    /// Steps it lost in all.
    pub lost: u32,
    /// A load on the slave's motor, if any (it loses steps while it lasts).
    pub load: Option<SlaveLoad>,
    /// The sync error (master less slave position, steps = counts; 0 before the first
    /// entry) from each cycle it changed in: `(cycle, error)`, in order (a change made to
    /// `position` by the caller is entered at the next clock).
    pub error_trace: Vec<(u64, i64)>,
    load_pulses: u32,
    last_step: [bool; 2],
}

/// A load on the gantry's slave motor: in cycles `from..to` it loses one step pulse in
/// `every` (the `every`-th, `2 * every`-th, ... pulse of the load; `every` 1: a stall,
/// every pulse lost).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SlaveLoad {
    /// The first cycle of the load.
    pub from: u64,
    /// The cycle it ends at (`u64::MAX`: for good).
    pub to: u64,
    /// One pulse lost in this many (0 is taken as 1).
    pub every: u32,
}

impl GantryPlant {
    /// Both motors at 0.
    pub fn new(master: usize, slave: usize, enc_master: usize, enc_slave: usize) -> Self {
        GantryPlant {
            master,
            slave,
            enc_master,
            enc_slave,
            position: [0; 2],
            stall_steps: 0,
            lost: 0,
            load: None,
            error_trace: Vec::new(),
            load_pulses: 0,
            last_step: [false; 2],
        }
    }

    /// The encoder pins of the two channels set in `word`.
    fn encoders(&self, word: u64) -> u64 {
        let mut word = word;
        for (side, &channel) in [self.enc_master, self.enc_slave].iter().enumerate() {
            // x4 Gray code counting up: (A, B) = 00, 10, 11, 01.
            let (a, b) = match self.position[side].rem_euclid(4) {
                0 => (false, false),
                1 => (true, false),
                2 => (true, true),
                _ => (false, true),
            };
            word &= !(1 << (top_pins::input::ENC_A + channel as u32) | 1 << (top_pins::input::ENC_B + channel as u32));
            word |= u64::from(a) << (top_pins::input::ENC_A + channel as u32);
            word |= u64::from(b) << (top_pins::input::ENC_B + channel as u32);
        }
        word
    }

    /// Whether the slave's step pulse in `cycle` is lost (a stall, or the load's turn).
    fn slave_loses(&mut self, cycle: u64) -> bool {
        if self.stall_steps > 0 {
            self.stall_steps -= 1;
            return true;
        }
        match self.load {
            Some(load) if (load.from..load.to).contains(&cycle) => {
                self.load_pulses += 1;
                if self.load_pulses >= load.every.max(1) {
                    self.load_pulses = 0;
                    return true;
                }
                false
            }
            _ => false,
        }
    }

    /// The motors take the step pulses of the chip's outputs `outputs` in `cycle` (a
    /// rise of the step pin moves one step in the direction pin's sense).
    fn follow(&mut self, cycle: u64, outputs: u64) {
        use top_pins::output as o;
        for (side, &axis) in [self.master, self.slave].iter().enumerate() {
            let step = outputs >> o::pin_a(axis) & 1 != 0;
            let dir = outputs >> o::pin_b(axis) & 1 != 0;
            if step && !self.last_step[side] {
                if side == 1 && self.slave_loses(cycle) {
                    self.lost += 1;
                } else {
                    self.position[side] += if dir { 1 } else { -1 };
                }
            }
            self.last_step[side] = step;
        }
        let now = self.position[0] - self.position[1];
        if now != self.error_trace.last().map_or(0, |&(_, e)| e) {
            self.error_trace.push((cycle, now));
        }
    }
}

/// A difference between the RTL and the model at the chip's pins.
#[derive(Debug)]
pub struct PanelChipMismatch {
    /// The test.
    pub name: String,
    /// The first cycle whose outputs differ.
    pub cycle: u64,
    /// The model's packed outputs and panel pins.
    pub expected: (u64, u32),
    /// The RTL's.
    pub actual: (u64, u32),
}

impl fmt::Display for PanelChipMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: cycle {}: outputs model {:#018x} RTL {:#018x} (differ {:#x}), panel model {:#08x} RTL {:#08x} (differ {:#x})",
            self.name,
            self.cycle,
            self.expected.0,
            self.actual.0,
            self.expected.0 ^ self.actual.0,
            self.expected.1,
            self.actual.1,
            self.expected.1 ^ self.actual.1
        )
    }
}

impl std::error::Error for PanelChipMismatch {}

/// The Verilated gantry-card chip and its model side by side, with the keypad and the
/// gantry plant between their pins.
pub struct PanelChipLockstep {
    name: String,
    rtl: RtlPanelChip,
    model: Top,
    /// The keypad's keys closed now.
    pub keys: Keypad,
    schedule: VecDeque<(u64, u16)>,
    /// The gantry plant, if one is on the pins.
    pub plant: Option<GantryPlant>,
    outputs: u64,
    panel: u32,
    cycle: u64,
    /// The last cycle a step pin (any axis's `pin_a`) rose in.
    pub last_step_rise: Option<u64>,
    /// The first cycle of the halt now in force (the machine's `halt`: a safety fault
    /// or the gantry's alarm), `None` while not halted.
    pub halted_since: Option<u64>,
}

/// The panel pins of the model in [`panel_bits`]' layout.
fn model_panel(model: &Top) -> u32 {
    let p = model.outputs().panel;
    u32::from(p.col) << panel_bits::COL | u32::from(p.seg) << panel_bits::SEG | u32::from(p.dig) << panel_bits::DIG
}

impl PanelChipLockstep {
    /// Both sides at power-on; drive `rst` first. With `FINESTEP_WAVES` set, the RTL's
    /// waveform goes to `target/waves/<name>.vcd`.
    pub fn new(name: &str) -> Self {
        let mut rtl = RtlPanelChip::new();
        if std::env::var_os("FINESTEP_WAVES").is_some() {
            let path = std::path::PathBuf::from("target/waves").join(format!("{name}.vcd"));
            let _ = std::fs::create_dir_all("target/waves");
            if let Err(e) = rtl.trace_open(&path) {
                eprintln!("{name}: no waveform: {e}");
            }
        }
        let model = Top::new(panel_chip_params());
        let outputs = rtl.outputs();
        let panel = rtl.panel();
        PanelChipLockstep {
            name: name.to_string(),
            rtl,
            model,
            keys: Keypad::default(),
            schedule: VecDeque::new(),
            plant: None,
            outputs,
            panel,
            cycle: 0,
            last_step_rise: None,
            halted_since: None,
        }
    }

    /// The model.
    pub fn model(&self) -> &Top {
        &self.model
    }

    /// The chip's packed outputs in this cycle.
    pub fn outputs_now(&self) -> u64 {
        self.outputs
    }

    /// Clock edges run.
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// The panel pins in this cycle ([`panel_bits`]).
    pub fn panel(&self) -> u32 {
        self.panel
    }

    /// The keys closed become `closed` at the start of cycle `at` (changes in order of
    /// their cycles; an earlier cycle than the last scheduled is taken at once).
    pub fn schedule_keys(&mut self, at: u64, closed: u16) {
        self.schedule.push_back((at, closed));
    }

    /// Scheduled key changes not yet made.
    pub fn pending_keys(&self) -> usize {
        self.schedule.len()
    }

    fn one_cycle(&mut self, inputs: u64) -> Result<(), PanelChipMismatch> {
        while let Some(&(at, closed)) = self.schedule.front() {
            if at > self.cycle {
                break;
            }
            self.keys.closed = closed;
            self.schedule.pop_front();
        }
        let col = (self.panel >> panel_bits::COL) as u8 & 0xf;
        let rows = self.keys.rows(col);
        let mut word = inputs & !(0xf << top_pins::input::PANEL_ROW_N);
        word |= u64::from(rows & 0xf) << top_pins::input::PANEL_ROW_N;
        if let Some(plant) = &self.plant {
            word = plant.encoders(word);
        }
        self.rtl.step(word);
        self.model.step(&TopInputs::unpack(word));
        self.cycle += 1;
        let expected = (self.model.outputs().pack(), model_panel(&self.model));
        let actual = (self.rtl.outputs(), self.rtl.panel());
        if expected != actual {
            self.rtl.trace_close();
            return Err(PanelChipMismatch { name: self.name.clone(), cycle: self.cycle, expected, actual });
        }
        let step_pins = (0..self.model.params().n_axes).fold(0u64, |m, a| m | 1 << top_pins::output::pin_a(a));
        if actual.0 & !self.outputs & step_pins != 0 {
            self.last_step_rise = Some(self.cycle);
        }
        self.halted_since = match (self.model.halt(), self.halted_since) {
            (true, None) => Some(self.cycle),
            (true, since) => since,
            (false, _) => None,
        };
        self.outputs = actual.0;
        self.panel = actual.1;
        if let Some(plant) = &mut self.plant {
            plant.follow(self.cycle, self.outputs);
        }
        Ok(())
    }
}

impl PinTarget for PanelChipLockstep {
    fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
        for _ in 0..cycles {
            self.one_cycle(inputs).map_err(|e| BusError::Transport(Box::new(e)))?;
        }
        Ok(())
    }

    fn outputs(&self) -> u64 {
        self.outputs
    }
}

/// The gantry card's chip behind the host driver's SPI master at its pins.
pub type PanelMachine = Machine<SpiBus<PinHost<PanelChipLockstep>>>;

/// The card's start-up after `COMMAND.CLEAR_FAULTS`: the E-stop fault of power-up is
/// latched in the LED menu, which shows its ALARM page; the host acknowledges every
/// latched alarm whose input is low and shows the MODE page (a write of `PANEL_MENU`
/// with the page 0 and every other field 0: the card's mode forward, no override, no
/// display override). Returns the menu as it was before.
pub fn acknowledge_power_up<B: Bus>(machine: &mut Machine<B>) -> Result<PanelMenu, BusError> {
    let menu = machine.panel_menu()?;
    machine.clear_panel_alarms(0b1111)?;
    machine.bus().write(panel_menu::ADDR, panel_menu::PAGE.set(0, 0))?;
    machine.bus().wait(8)?;
    Ok(menu)
}

/// The character a 7-segment digit shows, from its segment pins (bit 0 = a .. bit 6 =
/// g; the decimal point, bit 7, ignored), by the glyph table of docs/spec/led_menu.md
/// written as segment letters; `'?'` for a pattern not in it.
pub fn glyph_of(segments: u8) -> char {
    const TABLE: [(char, &str); 24] = [
        ('0', "abcdef"),
        ('1', "bc"),
        ('2', "abdeg"),
        ('3', "abcdg"),
        ('4', "bcfg"),
        ('5', "acdfg"),
        ('6', "acdefg"),
        ('7', "abc"),
        ('8', "abcdefg"),
        ('9', "abcdfg"),
        ('A', "abcefg"),
        ('b', "cdefg"),
        ('C', "adef"),
        ('d', "bcdeg"),
        ('E', "adefg"),
        ('F', "aefg"),
        ('-', "g"),
        ('r', "eg"),
        ('n', "ceg"),
        ('y', "bcdfg"),
        ('c', "deg"),
        ('h', "cefg"),
        ('L', "def"),
        (' ', ""),
    ];
    let bits = |letters: &str| letters.bytes().fold(0u8, |w, l| w | 1 << (l - b'a'));
    TABLE.iter().find(|(_, s)| bits(s) == segments & 0x7f).map(|&(c, _)| c).unwrap_or('?')
}

/// What the LED display's pins showed ([`read_display`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DisplayReading {
    /// The 8 characters, digit 7 first (`'?'` for a digit never lit alone, or a
    /// pattern not in the glyph table).
    pub text: String,
    /// Digit 0's decimal point.
    pub point: bool,
}

/// Why the display could not be read from the pins.
#[derive(Debug, thiserror::Error)]
pub enum DisplayError {
    /// The bus failed while the display was watched.
    #[error(transparent)]
    Bus(#[from] BusError),
    /// More than one digit was enabled in one clock (the multiplexing is broken).
    #[error("cycle {cycle}: two digits lit at once (digit pins {digits:#04x})")]
    TwoDigitsLit {
        /// The cycle.
        cycle: u64,
        /// The digit pins.
        digits: u8,
    },
}

/// The 8 characters the display shows, read from the LED pins over two refreshes of the
/// display set by `scan` (each digit `16 * refresh_div + 16` clocks): each digit's
/// segments while it alone is enabled, and the decimal point of digit 0.
pub fn read_display(machine: &mut PanelMachine, scan: &PanelScan) -> Result<DisplayReading, DisplayError> {
    let digit_clocks = 16 * u64::from(scan.refresh_div) + 16;
    let mut chars = ['?'; 8];
    let mut point = false;
    for _ in 0..2 * 8 * digit_clocks + 8 {
        machine.bus().wait(1)?;
        let chip = machine.bus_ref().link().target();
        let panel = chip.panel();
        let digits = (panel >> panel_bits::DIG) as u8;
        let segments = (panel >> panel_bits::SEG) as u8;
        if digits.count_ones() > 1 {
            return Err(DisplayError::TwoDigitsLit { cycle: chip.cycle(), digits });
        }
        if digits != 0 {
            let i = digits.trailing_zeros() as usize;
            chars[i] = glyph_of(segments);
            if i == 0 {
                point = segments & 0x80 != 0;
            }
        }
    }
    Ok(DisplayReading { text: chars.iter().rev().collect(), point })
}
