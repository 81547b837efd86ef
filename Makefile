# pftrack developer entry points.  `make demo` and `make test` set everything up on a fresh machine.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.pftrack-installed

.PHONY: setup demo test test-experiments bench bench-kernels clean clean-kernels

setup: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

# Track the bundled real clip; writes demo_out/track.csv and demo_out/track.mp4.
demo: setup
	$(BIN)/pftrack demo --out demo_out

# The default test suite (fast, deterministic), on two processes (pytest-xdist; a test file stays on one).
# pytest's exit code 5 (no tests collected) is a failure.
test: setup
	@$(BIN)/python -m pytest -q -n 2 --dist loadfile; rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "pytest collected no tests: failing" >&2; fi; \
	exit $$rc

# The longer experiments left out of the default run (each reproduces a comparison a doc page reports).
test-experiments: setup
	@$(BIN)/python -m pytest -q -n 2 --dist loadfile -m experiment

clean: clean-kernels
	rm -rf $(VENV) demo_out build *.egg-info .pytest_cache

# Numba's on-disk cache of the compiled kernels (__pycache__/*.nbi, *.nbc).  A kernel's entry is keyed on its own
# file only: after editing a compiled helper that a kernel in another file calls or inlines, clear it.
clean-kernels:
	find pftrack -name '*.nbi' -delete -o -name '*.nbc' -delete

# Speed: pftrack bench (synthetic sweeps + dev sequences, OpenCV peers interleaved) and kernel micro-benchmarks.
bench: setup
	$(BIN)/pftrack bench --dev ../shared/data --out reports/bench

bench-kernels: setup
	$(BIN)/python -m pytest benchmarks -q --benchmark-columns=min,median,mean
