# wavecheck — the two commands a new user needs: `make demo` and `make test`.
SHELL := /bin/bash
PY    := .venv/bin/python
VENV_STAMP := .venv/.installed
# The virtual environment's interpreter: Debian's own Python where it is installed (the libpython
# sigrok-cli runs its decoders in; here it runs pure Python ~25 % faster than pyenv's build:
# bench/README.md, Round 7), else the first python3 on PATH. `make PYTHON3=...` chooses another.
PYTHON3 ?= $(firstword $(wildcard /usr/bin/python3) python3)

.PHONY: demo test test-all setup system-deps lint typecheck bench golden golden-check story fuzz clean

setup: $(VENV_STAMP) system-deps

$(VENV_STAMP): pyproject.toml
	@test -x $(PY) || { $(PYTHON3) -c 'import sys; assert sys.version_info >= (3, 11)' 2>/dev/null \
	  && $(PYTHON3) -m venv .venv; } || { rm -rf .venv; python3 -m venv .venv; }
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test,klipper]'
	$(PY) -m compileall -q wavecheck stepgen tools  # an editable install compiles nothing: 0.5 s -> 0.2 s start-up (bench/README.md)
	@touch $@

# Real components from Debian's packages: sigrok-cli (readers for other formats, cross-checks,
# the protocol decoder's tests), pulseview (the decoder drawn under Xvfb), chromium (the HTML
# report test), gtkwave + xvfb (the save-file test; gtkwave's fst2vcd reads FST), iverilog + ghdl
# (the simulators whose VCD, FST and GHW dumps the format tests compare), gcc-avr + avr-libc +
# binutils-avr + libelf-dev + patch (wavecheck simulate: grbl and simavr built from source).
# Installed when missing.
system-deps:
	@missing=""; \
	command -v sigrok-cli >/dev/null || missing="$$missing sigrok-cli"; \
	command -v pulseview  >/dev/null || missing="$$missing pulseview"; \
	command -v chromium   >/dev/null || missing="$$missing chromium"; \
	command -v gtkwave    >/dev/null || missing="$$missing gtkwave"; \
	command -v xvfb-run   >/dev/null || missing="$$missing xvfb xauth"; \
	command -v iverilog   >/dev/null || missing="$$missing iverilog"; \
	command -v ghdl       >/dev/null || missing="$$missing ghdl"; \
	command -v avr-gcc    >/dev/null || missing="$$missing gcc-avr avr-libc binutils-avr"; \
	test -f /usr/include/libelf.h    || missing="$$missing libelf-dev"; \
	command -v patch      >/dev/null || missing="$$missing patch"; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "installing from Debian:$$missing"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null; \
	  else \
	    echo "missing:$$missing — run: sudo apt-get install$$missing" >&2; exit 1; \
	  fi; \
	fi

# The main job on bundled examples: LinuxCNC's stepgen (the faithful model in this repository)
# driving a Gecko G202 with 11 us of base-thread latency, as in the seed's stepper-tuning
# chapter. At BASE_PERIOD 20 us the DIR hold is 20 - 11 = 9 us < 20 us; `stepgen plan` picks
# 16 us with dirhold = 2 periods, and the capture made with that plan passes.
DEMO_BAD  := captures/golden/g202-p20-worst-dirhold.vcd
DEMO_GOOD := captures/golden/g202-p16-dirhold2-worst.vcd
# the real capture ships (sigrok-dumps, public domain: captures/real/README.md)
GRBL      := captures/real/grbl_cnc_1.sr

demo: setup
	@mkdir -p out
	@echo "== 1. wavecheck info: a LinuxCNC stepgen trace, P = 20 us, 11 us worst-case latency =="
	.venv/bin/wavecheck info $(DEMO_BAD)
	@echo
	@echo "== 2. wavecheck check against the Gecko G202 datasheet (exit 1: a rule fails) =="
	.venv/bin/wavecheck check $(DEMO_BAD) --drive gecko-g202 \
	    --plot out/demo-g202-p20.png --html out/demo-g202-p20.html || test $$? -eq 1
	@echo
	@echo "== 3. stepgen plan: BASE_PERIOD and stepgen parameters for 11 us of latency =="
	.venv/bin/stepgen plan --drive gecko-g202 --latency 11us --base-period 16us --format hal
	@echo
	@echo "== 4. the planned configuration under the same worst-case latency passes =="
	.venv/bin/wavecheck check $(DEMO_GOOD) --drive gecko-g202
	@echo
	@echo "== 5. a real capture: Grbl on a 2 MHz FX2 analyzer, 48 s (sigrok-dumps; no DIR channel was recorded) =="
	.venv/bin/wavecheck check $(GRBL) --drive leadshine-dm542 --map 'step=STEP (Y axis)'
	@echo
	@echo "== 6. a whole machine in one run: two axes, roles told from the channels, each axis checked =="
	.venv/bin/wavecheck check captures/examples/two-axis.vcd --drive gecko-g202 || test $$? -eq 1
	@echo
	@echo "== 7. live: two seconds from sigrok's demo device (a counter: STEP on D3, DIR on D6), checked as it arrives =="
	.venv/bin/wavecheck watch --driver demo:analog_channels=0 --channel-group Logic --config pattern=incremental \
	  --time 2s --drive drv8825 --map step=D3,dir=D6 --snippets out/snippets --save out/demo-live.sr
	@echo
	@echo "pictures: out/demo-g202-p20.png (timing diagram + histograms), out/demo-g202-p20.html"

# make test: lint, types and every test but those marked slow (the corpora, sweeps, installs),
# within 10 minutes on two quiet cores; its last line says what did not run and why.
# make test-all (what .ci/run runs): the same and the slow tests too.
test: setup lint typecheck
	.venv/bin/pytest -n 2 -q -m "not slow"

test-all: setup lint typecheck
	.venv/bin/pytest -n 2 -q

typecheck:
	.venv/bin/mypy

lint:
	.venv/bin/ruff check wavecheck stepgen tools tests bench
	.venv/bin/ruff format --check wavecheck stepgen tools tests bench

bench: setup
	$(PY) -m pip install -q -e '.[bench]'
	$(PY) bench/run.py

# Longer fuzz run of every reader (the suite runs a bounded one); FUZZ_N mutants per reader.
FUZZ_N ?= 20000
fuzz: setup
	$(PY) -m tests.reliability.fuzz -n $(FUZZ_N)

# Development tools: tools/ is not installed; they run from the checkout (python -m tools.NAME).
golden: setup
	$(PY) -m tools.golden --write

golden-check: setup
	$(PY) -m tools.golden --check
	$(PY) -m tools.examples --check

story: setup
	$(PY) -m tools.story

clean:
	rm -rf .venv build *.egg-info .pytest_cache .mypy_cache .ruff_cache
