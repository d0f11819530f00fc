# One entry point for every check. `make run` and `make test` are the README's two commands.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
# Two cores on CI: build and test with both.
export CARGO_BUILD_JOBS ?= 2

.PHONY: run test test-rust test-python install install-test lint bench bench-quick bench-pybasin device-carry clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

# Release build of the extension (maturin through pip) with the runtime and plotting extras.
install: $(BIN)/python
	$(BIN)/python -m pip install -q ".[plot]"

# ncdump (Debian netcdf-bin) is used by one test to prove that plain netCDF tools read our files;
# install it when apt is usable (CI runs as root), else that one test skips with its reason.
install-test: $(BIN)/python
	command -v ncdump >/dev/null || { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null && \
	  (apt-get install -y -q netcdf-bin >/dev/null 2>&1 || \
	   (apt-get update -q >/dev/null 2>&1 && apt-get install -y -q netcdf-bin >/dev/null 2>&1)) ; } || true
	$(BIN)/python -m pip install -q ".[test]"

# The main job: a default sweep around the seed configuration -> netCDF + regime map + report.
run: install
	$(BIN)/tribosweep seed --out out
	$(BIN)/tribosweep sweep -o out/seed_sweep.nc --overwrite --plot out/seed_sweep.png
	$(BIN)/tribosweep info out/seed_sweep.nc

test-rust:
	cargo test --release --workspace --exclude tribosweep-py

# The tests, then every `>>>` example of the package (the installed one: the extension lives there).
test-python: install-test
	$(BIN)/python -m pytest -q tests
	$(BIN)/python -m pytest -q --doctest-modules --pyargs tribosweep

# Everything the tests need, then every test (Rust numerics, then the Python package), release-built.
test: test-rust test-python

# stubtest checks python/tribosweep/_core.pyi against the built extension, so lint installs it first.
lint: install-test
	$(BIN)/python -m pip install -q ruff
	cargo fmt --all -- --check
	cargo clippy --release --workspace --all-targets -- -D warnings
	$(BIN)/python -m ruff check python tests benches
	$(BIN)/python -m mypy.stubtest tribosweep._core

bench: install-test
	$(BIN)/python benches/bench_trajectories.py --n 1000
	$(BIN)/python benches/bench_frequency.py
	$(BIN)/python benches/bench_hopf.py
	$(BIN)/python benches/bench_branch.py
	$(BIN)/python benches/bench_sweep.py --points 100000 --memory-points 1000000
	$(BIN)/python benches/bench_census.py
	$(BIN)/python benches/bench_stribeck.py
	$(BIN)/python benches/work_precision.py --out bench_out

# The seed census against pybasin 0.2.0 (needs a Python 3.12 for pybasin: see benches/pybasin_env.sh).
bench-pybasin:
	bash benches/pybasin_env.sh
	.venv-pybasin/bin/python benches/bench_pybasin.py --samples 1024 --horizon 15

bench-quick: install-test
	$(BIN)/tribosweep bench --quick --out bench_out

# This build and its runtime dependencies as wheels, for a bench on a machine with no package index.
device-carry: install-test
	bash benches/device_carry.sh

clean:
	rm -rf target $(VENV) out bench_out .device-carry
