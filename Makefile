# The two commands of the README. Both create .venv on first use and install what they need.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
# Small dense fits (table-law splines) get slower, not faster, with BLAS threads on 2 cores.
export OPENBLAS_NUM_THREADS ?= 1
TEST_STAMP := $(VENV)/.installed-test
# Pinned versions of every dependency (`make lock` refreshes them).
CONSTRAINTS := constraints.txt
# The compiled solvers (numba, cache=True): the sweep's exact solver, its rigid figures' loops and the spring chain's
# kernels, compiled once here, after install and whenever their source changes, into
# explorer/dynamics/__pycache__, so that no sweep, chain scene or test worker pays the ~30 s and
# ~10 s of compilation; numba replaces its cache files atomically, so concurrent test workers
# that find it stale each compile and none breaks. The exact solver's kernel is several modules
# that read constants of the Python solver's: any of those sources changing discards its cache
# (explorer/dynamics/kernel_stamp.py), so they are all listed here. The sweep's kernels are also
# compiled ahead of time (numba.pycc, gcc) into extension modules beside their sources, which a
# sweep uses while they were built from the current sources and then loads no numba (~0.5 s of
# CPU a process: explorer/core/aot.py, docs/benchmarks/sweep.md #27.3).
KERNEL := $(wildcard explorer/dynamics/kernel_*.py) explorer/dynamics/exact_kernel.py explorer/dynamics/free_vibration.py \
	explorer/dynamics/exact.py explorer/dynamics/exact_events.py explorer/dynamics/exact_grid.py \
	explorer/dynamics/exact_phase.py explorer/dynamics/exact_steps.py explorer/dynamics/phases.py \
	explorer/dynamics/chain_kernels.py explorer/mechanics/sweep_kernels.py explorer/mechanics/sweep_loops.py explorer/core/aot.py explorer/core/aot_build.py
KERNEL_STAMP := $(VENV)/.kernel-compiled

.PHONY: run test bench docs lock clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): pyproject.toml $(CONSTRAINTS) | $(BIN)/python
	$(BIN)/python -m pip install --quiet -c $(CONSTRAINTS) -e .
	touch $@

$(TEST_STAMP): pyproject.toml $(CONSTRAINTS) | $(BIN)/python
	$(BIN)/python -m pip install --quiet -c $(CONSTRAINTS) -e ".[test]"
	touch $@ $(STAMP)

$(KERNEL_STAMP): $(KERNEL) $(STAMP)
	$(BIN)/python -m explorer.dynamics.exact_kernel --warm
	$(BIN)/python -m explorer.dynamics.chain_exact
	$(BIN)/python -m explorer.mechanics.sweep_kernels
	$(BIN)/python -m explorer.dynamics.exact_kernel --aot
	$(BIN)/python -m explorer.mechanics.sweep_loops --aot
	touch $@

# Not after $(KERNEL_STAMP): the first page needs no compiled solver; `explorer serve` compiles
# them in the background once the page is served, and the page says so meanwhile.
run: $(STAMP)
	$(BIN)/explorer serve $(SCENE)

test: $(TEST_STAMP) $(KERNEL_STAMP)
	$(BIN)/python -m pytest -q -n auto

# The documentation site into site/ (mkdocs.yml; strict: a warning or a broken link fails it;
# the reference pages are generated from the code by docs/_hooks/generate.py).
docs: $(TEST_STAMP)
	$(BIN)/mkdocs build --strict --quiet
	@echo "site/index.html"

bench: $(STAMP) $(KERNEL_STAMP)
	$(BIN)/python benchmarks/run_all.py

# Resolve the newest releases that pyproject.toml allows in a scratch venv and pin them; then
# `make clean test` proves them before constraints.txt is committed.
lock:
	rm -rf .venv-lock
	$(PYTHON) -m venv .venv-lock
	.venv-lock/bin/python -m pip install --quiet --upgrade pip
	.venv-lock/bin/python -m pip install --quiet -e ".[test]"
	{ sed -n '1,2p' $(CONSTRAINTS); .venv-lock/bin/python -m pip freeze --exclude-editable | grep -v '^#'; } > $(CONSTRAINTS).new
	mv $(CONSTRAINTS).new $(CONSTRAINTS)
	rm -rf .venv-lock

clean:
	rm -rf $(VENV) build site *.egg-info explorer/*/_*_aot.*.so
