# `make demo` and `make test` set up .venv from nothing, then run.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: install demo lint test notebooks bench bench-quick clean

$(STAMP): pyproject.toml
	@$(PYTHON) -c 'import sys; sys.exit(0 if sys.version_info >= (3, 11) else "rotor needs Python >= 3.11 (set PYTHON=...)")'
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/rotor demo --plot out

# the house rules first (seconds), then the suite
lint: $(STAMP)
	$(VENV)/bin/ruff check rotor tests benchmarks
	$(VENV)/bin/ruff format --check rotor tests benchmarks
	$(VENV)/bin/lint-imports --no-cache
	$(VENV)/bin/mypy

test: lint
	$(PY) -m pytest -q

# re-execute the notebooks in their full form and save their outputs (a few minutes)
notebooks: $(STAMP)
	$(PY) -m pytest -q -p no:cacheprovider --nbmake --overwrite notebooks

# every figure in benchmarks/README.md (about 1.5 h on 2 CPUs; numba for the baseline)
bench: $(STAMP)
	$(PY) -m pip install --quiet -e '.[test,bench]'
	$(PY) benchmarks/defaults.py
	$(PY) benchmarks/fidelity_differences.py
	$(PY) benchmarks/compile_time.py
	$(PY) benchmarks/work_precision.py --cap 20
	$(PY) benchmarks/simulator_accuracy.py
	$(PY) benchmarks/simulator_speed.py
	$(PY) benchmarks/logged_speed.py
	$(PY) benchmarks/seed004_accuracy.py
	$(PY) benchmarks/flywheel.py

# the quick forms (a few minutes)
bench-quick: $(STAMP)
	$(PY) -m pip install --quiet -e '.[test,bench]'
	$(PY) benchmarks/work_precision.py --quick
	$(PY) benchmarks/compile_time.py --quick
	$(PY) benchmarks/simulator_speed.py --quick

clean:
	rm -rf $(VENV) out .pytest_cache build *.egg-info
