# wavecheck — the two commands a new user needs: `make demo` and `make test`.
SHELL := /bin/bash
PY    := .venv/bin/python
VENV_STAMP := .venv/.installed
DEMO  := captures/demo

.PHONY: demo test setup system-deps lint typecheck bench golden golden-check story fuzz clean

setup: $(VENV_STAMP) system-deps

$(VENV_STAMP): pyproject.toml
	@test -x $(PY) || python3 -m venv .venv
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	@touch $@

# Real components from Debian's packages: sigrok-cli (readers for other formats, cross-checks)
# and chromium (the HTML report test). Installed when missing; never assumed.
system-deps:
	@missing=""; \
	command -v sigrok-cli >/dev/null || missing="$$missing sigrok-cli"; \
	command -v chromium   >/dev/null || missing="$$missing chromium"; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "installing from Debian:$$missing"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null; \
	  else \
	    echo "missing:$$missing — run: sudo apt-get install$$missing" >&2; exit 1; \
	  fi; \
	fi

demo: setup
	@echo "== wavecheck info: a real grbl capture (2 MHz, 48 s) =="
	.venv/bin/wavecheck info ../shared/captures/sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr
	@echo
	@echo "== wavecheck check: the grbl capture against a Leadshine DM542 =="
	-.venv/bin/wavecheck check ../shared/captures/sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr \
	    --drive leadshine-dm542 --map 'step=STEP (Y axis)'

test: setup
	.venv/bin/ruff check wavecheck stepgen tests bench
	.venv/bin/mypy
	.venv/bin/pytest -n 2 -q

lint:
	.venv/bin/ruff check wavecheck stepgen tests bench

bench: setup
	$(PY) bench/run.py

# Longer fuzz run of every reader (the suite runs a bounded one); FUZZ_N mutants per reader.
FUZZ_N ?= 20000
fuzz: setup
	$(PY) -m tests.reliability.fuzz -n $(FUZZ_N)

golden: setup
	$(PY) -m stepgen.golden --write

golden-check: setup
	$(PY) -m stepgen.golden --check

story: setup
	$(PY) -m stepgen.story

clean:
	rm -rf .venv build *.egg-info .pytest_cache .mypy_cache .ruff_cache
