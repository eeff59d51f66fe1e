# `make demo` and `make test` set up .venv from nothing, then run.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: install demo lint lint-quick docs docs-build reference test fuzz wheel-check notebooks bench bench-quick clean

# uv installs the same versions as pip, several times faster (its downloads in parallel);
# pip does it where uv cannot be installed. Where Python is told not to write bytecode
# (PYTHONDONTWRITEBYTECODE set), the install writes it once: else every process would
# compile JAX's sources again (about 3.5 s of every command's start here, and of every
# test's child process)
COMPILE := $(if $(PYTHONDONTWRITEBYTECODE),--compile-bytecode,)
$(STAMP): pyproject.toml
	@$(PYTHON) -c 'import sys; sys.exit(0 if sys.version_info >= (3, 11) else "rotor needs Python >= 3.11 (set PYTHON=...)")'
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip uninstall --quiet --yes rotor  # the distribution's name before crank-rotor
	$(PY) -m pip install --quiet --disable-pip-version-check uv \
	  && $(VENV)/bin/uv pip install --quiet --python $(PY) $(COMPILE) -e '.[test,docs]' \
	  || $(PY) -m pip install --quiet -e '.[test,docs]'
	$(if $(PYTHONDONTWRITEBYTECODE),$(PY) -m compileall -q rotor,)
	@touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/rotor demo --plot out

# the static checks first (seconds), then the suite
lint: lint-quick
	$(VENV)/bin/mypy

lint-quick: $(STAMP)
	$(VENV)/bin/ruff check rotor tests benchmarks
	$(VENV)/bin/ruff format --check rotor tests benchmarks
	$(VENV)/bin/lint-imports --no-cache

# the documentation site: `make docs` serves it on http://127.0.0.1:8000 and rebuilds on
# every change; `make test` builds it strictly (a broken reference fails) into build/site
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs serve

docs-build: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --quiet

# the generated text of docs/cli.md, docs/reference/engine-file.md and docs/reference/wheels.md
# (the commands' help, the table of commands, the engine-file keys, the standard wheels)
# written afresh from the code into the pages
reference: $(STAMP)
	$(PY) docs/hooks.py

# two worker processes (the CI machine has two cores), each taking whole test files, so that
# a file's fixtures are computed once, in the order of the folders (a worker's next file is
# usually its last one's neighbour and reuses what that compiled; the documentation and
# notebook tests come late and read what the rest put into the compilation cache; taking the
# longest files first was no faster); property tests draw the same examples on every run.
# ruff and the import contracts first (a second); mypy and the strict site build (about
# 100 s on one core) run beside the suite, their output after it: the pytest workers start
# at once instead of waiting for them, and the run fails if any of the three fails
test: lint-quick
	@mkdir -p build
	@{ $(VENV)/bin/mypy && $(MAKE) --no-print-directory docs-build; } \
	  > build/static-checks.log 2>&1 & checks=$$!; \
	$(PY) -m pytest -q -n 2 --dist loadfile --no-loadscope-reorder --durations=30; suite=$$?; \
	wait $$checks; static=$$?; \
	echo "mypy and mkdocs build --strict:"; cat build/static-checks.log; \
	if [ $$static -ne 0 ]; then echo "make test: mypy or the site build failed (above)"; fi; \
	exit $$(( suite || static ))

# the property and fuzz tests with new random draws (tests/conftest.py); what they find
# becomes an explicit example in the test
fuzz: $(STAMP)
	ROTOR_FUZZ=1 $(PY) -m pytest -q -n 2 -p no:cacheprovider tests/cli/test_fuzz.py tests/dynamics/test_properties.py

# the wheel installs in a clean virtualenv (its dependencies from the package index) and
# runs `rotor demo` there (about a minute)
wheel-check: $(STAMP)
	ROTOR_WHEEL_CHECK=1 $(PY) -m pytest -q -p no:cacheprovider tests/project/test_packaging.py

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
	$(PY) benchmarks/textbook_tables.py
	$(PY) benchmarks/flywheel.py

# the quick forms (a few minutes)
bench-quick: $(STAMP)
	$(PY) -m pip install --quiet -e '.[test,bench]'
	$(PY) benchmarks/work_precision.py --quick
	$(PY) benchmarks/compile_time.py --quick
	$(PY) benchmarks/simulator_speed.py --quick

clean:
	rm -rf $(VENV) out .pytest_cache build dist *.egg-info
