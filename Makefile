# decon-bench: every target creates/refreshes .venv first, so each works as the first command.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
EXTRAS ?= ray,dev
PROFILE ?= quick
WORKERS ?= 0
PYTEST_ARGS ?=

.PHONY: install test test-slow lint format bench stability perf figures report clean

install: $(STAMP)

# The stamp is older than pyproject.toml when dependencies changed: reinstall then.
$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[$(EXTRAS)]"
	@touch $(STAMP)

test: $(STAMP)
	$(PY) -m pytest -m "not slow" -q $(PYTEST_ARGS)

test-slow: $(STAMP)
	$(PY) -m pytest -m slow -q $(PYTEST_ARGS)

lint: $(STAMP)
	$(PY) -m ruff check systems models bench tests
	$(PY) -m ruff format --check systems models bench tests

format: $(STAMP)
	$(PY) -m ruff format systems models bench tests
	$(PY) -m ruff check --fix systems models bench tests

bench: $(STAMP)
	$(PY) -m bench bench --profile $(PROFILE) --workers $(WORKERS)

stability: $(STAMP)
	$(PY) -m bench stability --profile $(PROFILE)

perf: $(STAMP)
	$(PY) -m bench perf

figures: $(STAMP)
	$(PY) -m bench figures

report: $(STAMP)
	$(PY) -m bench report

clean:
	rm -rf $(VENV) .cache .pytest_cache
