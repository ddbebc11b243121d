# The README's two commands: `make run` (main study) and `make test` (whole test suite).
# Each creates the virtual environment it needs on first use (python3 -m venv + pip install -e).

PYTHON ?= python3
VENV   ?= .venv
PIP     = $(VENV)/bin/python -m pip
PY      = $(VENV)/bin/python
OUT    ?= results/linear_pid_accuracy

.PHONY: run test lint docs install install-test clean

$(VENV)/.core: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PIP) install --upgrade pip
	$(PIP) install -e .
	touch $@

$(VENV)/.docs: $(VENV)/.core
	$(PIP) install -e ".[docs]"
	touch $@

$(VENV)/.test: $(VENV)/.core
	$(PIP) install -e ".[test,mjx,brax,cmaes]"
	touch $@

install: $(VENV)/.core
install-test: $(VENV)/.test

run: $(VENV)/.core
	$(PY) -m experiments run linear_pid_accuracy --out $(OUT)

# one worker per core; a test file stays on one worker so its compiled functions are reused;
# the 25 slowest tests are listed at the end (the suite's time is mostly compilation); a worker that
# crashes ends the run (pytest-xdist 3.8 hung after replacing a crashed worker; the crashes came from
# the per-process memory-map limit, now kept away by tests/process_maps.py)
test: $(VENV)/.test
	$(PY) -m pytest -n auto --dist loadfile --durations=25 --max-worker-restart=0

# ruff lint and format check (configured in pyproject.toml)
lint: $(VENV)/.test
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

# the API reference site into site/; --strict: a broken reference or docstring fails the build
docs: $(VENV)/.docs
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --site-dir site

clean:
	rm -rf $(VENV) .jax_cache .pytest_cache results site
