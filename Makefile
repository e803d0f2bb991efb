# decon-bench: every target creates/refreshes .venv first, so each works as the first command.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
EXTRAS ?= ray,dev
PROFILE ?= quick
WORKERS ?= 0
PYTEST_ARGS ?=
# The environment is installed from a lock file (exact versions and sha256 hashes, linux
# x86_64, Python 3.11): requirements/cpu.txt, or requirements/cuda.txt with ACCEL=cuda.
# LOCK= (empty) installs the loose ranges of pyproject.toml instead (other platforms).
ACCEL  ?= cpu
LOCK   ?= requirements/$(ACCEL).txt
# The lock tool lives in its own venv, never in .venv.
UV_VERSION ?= 0.13.9
TOOLS  := .cache/tools
UV     := $(TOOLS)/bin/uv
UV_COMPILE = $(UV) pip compile pyproject.toml --extra ray --extra dev \
	--python-version 3.11 --python-platform x86_64-manylinux_2_28 \
	--generate-hashes --annotation-style line --custom-compile-command "make lock" --quiet

.PHONY: install lock upgrade test test-slow lint format bench stability perf figures report clean

install: $(STAMP)

# The stamp is older than the lock or pyproject.toml when dependencies changed: reinstall then.
$(STAMP): pyproject.toml $(LOCK)
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
ifeq ($(strip $(LOCK)),)
	$(PY) -m pip install --quiet -e ".[$(EXTRAS)]"
else
	$(PY) -m pip install --quiet --require-hashes -r $(LOCK)
	$(PY) -m pip install --quiet --no-deps -e .
endif
	@touch $(STAMP)

$(UV):
	$(PYTHON) -m venv $(TOOLS)
	$(TOOLS)/bin/pip install --quiet "uv==$(UV_VERSION)"

# Re-resolve the locks after a change of pyproject.toml, keeping every pin that still fits.
lock: $(UV)
	$(UV_COMPILE) -o requirements/cpu.txt
	$(UV_COMPILE) --extra cuda -o requirements/cuda.txt

# Move every pin to the newest release that pyproject.toml allows, reinstall, run the tests.
upgrade: $(UV)
	$(UV_COMPILE) --upgrade -o requirements/cpu.txt
	$(UV_COMPILE) --upgrade --extra cuda -o requirements/cuda.txt
	$(MAKE) install
	$(MAKE) test

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
	$(PY) -m bench stability --profile $(PROFILE) --workers $(WORKERS)

perf: $(STAMP)
	$(PY) -m bench perf

figures: $(STAMP)
	$(PY) -m bench figures

report: $(STAMP)
	$(PY) -m bench report

clean:
	rm -rf $(VENV) .cache .pytest_cache
