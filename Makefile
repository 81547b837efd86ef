# pftrack developer entry points.  `make demo` and `make test` set everything up on a fresh machine.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.pftrack-installed

.PHONY: setup demo test bench bench-kernels clean

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

clean:
	rm -rf $(VENV) demo_out build *.egg-info .pytest_cache

# Speed: pftrack bench (synthetic sweeps + dev sequences, OpenCV peers interleaved) and kernel micro-benchmarks.
bench: setup
	$(BIN)/pftrack bench --dev ../shared/data --out reports/bench

bench-kernels: setup
	$(BIN)/python -m pytest benchmarks -q --benchmark-columns=min,median,mean
