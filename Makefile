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

.PHONY: install lock upgrade test golden test-slow lint format bench bench-seeds bench-all compare replicate stability perf figures report clean mujoco-data \
	paper-core paper-core-status paper-core-pause paper-core-resume paper-core-drain paper-core-stop paper-core-report paper-gpu gpu-wheels \
	paper-k paper-k-status paper-k-pause paper-k-resume paper-k-drain paper-k-stop

install: $(STAMP)

# The stamp is older than the lock or pyproject.toml when dependencies changed: reinstall then
# (a campaign's start does so only when no campaign runs from this venv).
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

# The fast tests in TEST_WORKERS processes (pytest-xdist): 1.3x faster on 2 cores (475 s
# against 619 s of pytest on a cold cache); TEST_WORKERS=0 runs them in-process.
TEST_WORKERS ?= 2
test: $(STAMP)
	$(PY) -m pytest -m "not slow" -q -n $(TEST_WORKERS) --dist loadfile $(PYTEST_ARGS)

# the committed report of the synthetic folders (tests/golden/), rewritten from today's code
golden: $(STAMP)
	DECON_UPDATE_GOLDEN=1 $(PY) -m pytest -q tests/test_figures.py -k golden $(PYTEST_ARGS)

test-slow: $(STAMP)
	$(PY) -m pytest -m slow -q $(PYTEST_ARGS)

lint: $(STAMP)
	$(PY) -m ruff check systems models collect bench tests examples
	$(PY) -m ruff format --check systems models collect bench tests examples

format: $(STAMP)
	$(PY) -m ruff format systems models collect bench tests examples
	$(PY) -m ruff check --fix systems models collect bench tests examples

# Your runs go to $(RESULTS) (git-ignored); the committed reference results are under
# results/reference/<budget>/, read-only (results/README.md). `make bench` ends with the
# comparison against the reference of its profile ($(RESULTS)/COMPARE.md). Maintainers
# regenerate a reference with RESULTS=results/reference/quick.
RESULTS ?= results/own
REFERENCE ?= results/reference/quick

# `make bench`: the Deconstructing paper's experiments and the stability cases; `make
# bench-seeds`: the seeds' (the HNN, LNN and VIN papers'); each fits a 2-core laptop's 30
# minutes, both together do not. `make bench-all`: both, one after the other.
bench: $(STAMP)
	$(PY) -m bench --results $(RESULTS) bench --profile $(PROFILE) --workers $(WORKERS) --papers deconstructing

bench-seeds: $(STAMP)
	$(PY) -m bench --results $(RESULTS) bench --profile $(PROFILE) --workers $(WORKERS) --papers hnn,lnn,vin

bench-all: bench bench-seeds

# Any two results folders side by side (default: the quick reference against your runs).
compare: $(STAMP)
	$(PY) -m bench --results $(RESULTS) compare $(REFERENCE) $(RESULTS) --out $(RESULTS)/COMPARE.md

# The replication: the claim experiments again on the profile's replication seeds
# (quick: 5-9), stored beside the runs of `make bench`; the report judges every claim on both.
replicate: $(STAMP)
	$(PY) -m bench --results $(RESULTS) campaign --profile $(PROFILE) --replication --workers $(WORKERS)
	$(PY) -m bench --results $(RESULTS) figures
	$(PY) -m bench --results $(RESULTS) report

stability: $(STAMP)
	$(PY) -m bench --results $(RESULTS) stability --profile $(PROFILE) --workers $(WORKERS)

# The MuJoCo tasks' data (Fig. 7): a SAC policy trained MUJOCO_STEPS env steps per task on
# this CPU, its whole recorded buffer saved to data/mujoco (resumable: checkpoints in the cache).
MUJOCO_TASKS ?= HopperFull-v0 SwimmerFull-v0 HalfCheetahFull-v0
MUJOCO_STEPS ?= 200000
mujoco-data: $(STAMP)
	@for t in $(MUJOCO_TASKS); do \
		$(PY) -m bench data mujoco $$t --steps $(MUJOCO_STEPS) || exit 1; done

perf: $(STAMP)
	$(PY) -m bench --results $(RESULTS) perf

figures: $(STAMP)
	$(PY) -m bench --results $(RESULTS) figures

report: $(STAMP)
	$(PY) -m bench --results $(RESULTS) report

# The paper-core campaign: the paper's budget on the cells each verdict needs, niced in
# the background, resumable at any moment (runs are content-addressed). Its process group is
# the campaign: pause/resume/stop act on all its workers at once. setsid gives it its own
# scheduler autogroup, where Linux (sched_autogroup_enabled = 1) ignores the nice level against
# other sessions: the autogroup itself is niced too, or the campaign takes half the machine.
# The child nices its own autogroup after setsid (from outside, a race could nice the caller's).
# `env kill`: the shell's builtin kill (dash) does not signal a process group.
# Three phases, so that each paper-core verdict is judged again on a disjoint seed set (the
# replication rule): the replication seeds (5-9) of the claims whose verdict on the selection's
# own seeds (0-4) is signed, then the own seeds of the rest, then the rest's replication seeds.
CAMPAIGN_DIR ?= results/reference/paper
CAMPAIGN_PID := .cache/paper-core.pid
CAMPAIGN_LOG := .cache/paper-core.log
CAMPAIGN_DRAIN := $(abspath .cache/paper-core.drain)
CAMPAIGN_WORKERS ?= 2
CAMPAIGN_PROFILE ?= paper-core
# claims run before the three phases, reading by reading on both seed sets (campaign
# --by-reading: own cells, then further readings cheapest run first; e.g. CAMPAIGN_FIRST=16:
# the runs an open piece of work waits for, to a replicated verdict); empty: the phases alone
CAMPAIGN_FIRST ?=
campaign_pid = $$(cat $(CAMPAIGN_PID) 2>/dev/null)
campaign_alive = test -f $(CAMPAIGN_PID) && kill -0 $(campaign_pid) 2>/dev/null

paper-core:
	@mkdir -p .cache
	@if $(campaign_alive); then echo "paper-core: already running (process group $(campaign_pid))"; \
	else $(MAKE) --no-print-directory $(STAMP) && rm -f $(CAMPAIGN_DRAIN); DECON_DRAIN=$(CAMPAIGN_DRAIN) FIRST="$(CAMPAIGN_FIRST)" \
		setsid nohup sh -c 'echo 19 > /proc/self/autogroup 2>/dev/null; \
		{ [ -z "$$FIRST" ] || nice -n 19 "$$@" --claims "$$FIRST" --by-reading; } && \
		nice -n 19 "$$@" --replication --signed && nice -n 19 "$$@" && \
		exec nice -n 19 "$$@" --replication' sh \
		$(PY) -m bench --results $(CAMPAIGN_DIR) campaign \
		--profile paper-core --workers $(CAMPAIGN_WORKERS) > $(CAMPAIGN_LOG) 2>&1 & \
		echo $$! > $(CAMPAIGN_PID); \
		echo "paper-core: started in the background (process group $$(cat $(CAMPAIGN_PID)), nice 19, log $(CAMPAIGN_LOG))"; fi

# A status reads the venv it finds (it installs one only where there is none): it never
# reinstalls one under a running campaign.
VENV_FOUND = $(if $(wildcard $(STAMP)),,$(STAMP))
paper-core-status: $(VENV_FOUND)
	@if $(campaign_alive); then state=$$(ps -o stat= -p $(campaign_pid) | cut -c1); \
		if [ "$$state" = T ]; then echo "paper-core: paused (process group $(campaign_pid))"; \
		else echo "paper-core: running (process group $(campaign_pid))"; fi; \
	else echo "paper-core: not running"; fi
	@$(PY) -m bench --results $(CAMPAIGN_DIR) estimate --profile $(CAMPAIGN_PROFILE) --workers $(CAMPAIGN_WORKERS) $(CAMPAIGN_ESTIMATE)

paper-core-pause:
	@$(campaign_alive) && env kill -s STOP -- -$(campaign_pid) && echo "paper-core: paused" || echo "paper-core: not running"

paper-core-resume:
	@$(campaign_alive) && env kill -s CONT -- -$(campaign_pid) && echo "paper-core: resumed" || echo "paper-core: not running"

# Let the runs in flight finish (they are stored), start no new one; then the campaign ends.
paper-core-drain:
	@$(campaign_alive) && touch $(CAMPAIGN_DRAIN) && env kill -s CONT -- -$(campaign_pid) && \
		echo "paper-core: draining: the runs in flight finish, none starts (make paper-core-status says when it has ended)" || \
		echo "paper-core: not running"

paper-core-stop:
	@$(campaign_alive) && env kill -s CONT -- -$(campaign_pid) && env kill -s TERM -- -$(campaign_pid) && \
		echo "paper-core: stopped (make paper-core resumes)" || echo "paper-core: not running"

# The paper's other numbers of links: the paper-k selection (k = 1, 3, 4 of Figs. 2-5, the
# paper's per-run budget) as the same kind of background campaign, one claim at a time, each on
# seeds 0-4 then 5-9, fewer links first (PAPER_K_CLAIMS): Fig. 5's NODE+SO and HNN+SO (claim 4,
# the headline), Fig. 4's NODE and HNN (claim 3: its other cells are claim 4's, so its own cost
# a fifth of claim 4's hours), Fig. 2's energy cells (claim 1: none of its own, it is judged
# once claims 3 and 4 are), Fig. 3's weights at k >= 3 (claim 2). Claims 4 and 3 are stored on
# seeds 0-4, so this order runs claim 4's replication first. It shares paper-core's process-group file: one campaign runs at a time, and the
# paper-k-* verbs are paper-core's. Rows hash as the paper profile's, a GPU's count alike.
PAPER_K_CLAIMS ?= 4 3 1 2
paper-k:
	@mkdir -p .cache
	@if $(campaign_alive); then echo "paper-k: a campaign is already running (process group $(campaign_pid))"; \
	else $(MAKE) --no-print-directory $(STAMP) && rm -f $(CAMPAIGN_DRAIN); DECON_DRAIN=$(CAMPAIGN_DRAIN) CLAIMS="$(PAPER_K_CLAIMS)" \
		setsid nohup sh -c 'echo 19 > /proc/self/autogroup 2>/dev/null; \
		for c in $$CLAIMS; do nice -n 19 "$$@" --claims $$c && \
			nice -n 19 "$$@" --replication --claims $$c || exit 1; done' sh \
		$(PY) -m bench --results $(CAMPAIGN_DIR) campaign \
		--profile paper-k --workers $(CAMPAIGN_WORKERS) > $(CAMPAIGN_LOG) 2>&1 & \
		echo $$! > $(CAMPAIGN_PID); \
		echo "paper-k: started in the background (process group $$(cat $(CAMPAIGN_PID)), nice 19, log $(CAMPAIGN_LOG))"; fi

paper-k-status: $(VENV_FOUND)
	@$(MAKE) --no-print-directory paper-core-status CAMPAIGN_PROFILE=paper-k \
		CAMPAIGN_ESTIMATE="--claims '$(PAPER_K_CLAIMS)'"

paper-k-pause: paper-core-pause
paper-k-resume: paper-core-resume
paper-k-drain: paper-core-drain
paper-k-stop: paper-core-stop

# The paper profile's cells that the CPU campaign leaves out, on a GPU machine (the device tool):
# claim 4's and Fig. 2's k = 1-4 with the cells they share (claims 1, 3), claim 2's weight grid,
# then L1/L2, the damped and relativistic extras; seeds 0-9; ensembles on (auto on an
# accelerator). No install: GPU_PY must hold jax, equinox, diffrax, optax, optimistix, pandas,
# pyarrow, scipy and matplotlib (the device image's python3 does). Resumable (runs are
# content-addressed); each experiment stops at GPU_SECONDS from the start, its stored rows kept.
# GPU_OUT (the device's $OUT): the rows this call stored packed into GPU_OUT/rows.tgz every 20 s
# and at the end, so that a call stopped at its limit still brings back every run it stored (the
# device returns 8 files at most, 16 MiB each: never the row files themselves, nor the rows that
# travelled). Packages the device's image lacks travel as wheels in .whl/ (ignored; `make
# gpu-wheels` fetches MuJoCo's, which the MuJoCo runs need to replay their transitions; name
# .whl in the call's carry): installed into a temporary folder first. GPU_WORKERS > 1: that many sweep
# processes share the GPU, each with its share of its memory (for runs that train alone:
# pixels, fresh-state objectives). The campaign's own cells go the same way (GPU_PROFILE=
# paper-core GPU_DIR=results/reference/paper). GPU_MODELS: only these trained models (sweep's
# --models). The working tree travels to the device (64 MiB at most): move results/reference
# out of it for the call (docs/studies/campaign.md, "The MuJoCo call, prepared").
# On the device: make paper-gpu GPU_OUT=$OUT
# Here: tar xzf <files_at>/rows.tgz --skip-old-files -C $(GPU_DIR), then figures and report.
GPU_PY ?= python3
GPU_DIR ?= results/reference/paper_gpu
GPU_PROFILE ?= paper
GPU_SEEDS ?= 0,1,2,3,4,5,6,7,8,9
GPU_EXPERIMENTS ?= coordinates energy second_order symplectic loss damped relativistic
GPU_SECONDS ?= 540
GPU_OUT ?=
GPU_WORKERS ?= 1
GPU_MODELS ?=
paper-gpu:
	@end=$$(( $$(date +%s) + $(GPU_SECONDS) )); mkdir -p $(GPU_DIR)/.rows; start=$$(mktemp); \
	if [ -d .whl ]; then site=$$(mktemp -d); $(GPU_PY) -m pip install -q --no-index --no-deps \
		--no-compile --no-cache-dir --target $$site .whl/*.whl || exit 1; \
		export PYTHONPATH=$$site$${PYTHONPATH:+:$$PYTHONPATH}; fi; \
	pack() { [ -z "$(GPU_OUT)" ] || { (cd $(GPU_DIR) && find .rows -type f -newer $$start) > $$start.list && \
		tar czf $(GPU_OUT)/rows.part -C $(GPU_DIR) -T $$start.list && \
		mv $(GPU_OUT)/rows.part $(GPU_OUT)/rows.tgz; }; }; \
	if [ -n "$(GPU_OUT)" ]; then (while sleep 20; do pack; done) & packer=$$!; fi; \
	if [ $(GPU_WORKERS) -gt 1 ]; then \
		export XLA_PYTHON_CLIENT_MEM_FRACTION=$$(awk "BEGIN{print 0.9/($(GPU_WORKERS)+1)}"); fi; \
	for e in $(GPU_EXPERIMENTS); do \
		left=$$(( end - $$(date +%s) )); \
		if [ $$left -le 20 ]; then echo "paper-gpu: $(GPU_SECONDS) s spent; $$e and after not started"; break; fi; \
		echo "paper-gpu: $$e ($$left s left)"; \
		timeout $$left $(GPU_PY) -m bench --results $(GPU_DIR) sweep $$e --profile $(GPU_PROFILE) \
			--seeds $(GPU_SEEDS) $(if $(GPU_MODELS),--models $(GPU_MODELS)) --workers $(GPU_WORKERS) --no-progress || echo "paper-gpu: $$e stopped (exit $$?)"; \
	done; \
	[ -z "$${packer:-}" ] || kill $$packer; pack; \
	echo "paper-gpu: $$(find $(GPU_DIR)/.rows -type f -newer $$start | wc -l) new rows, $$(ls $(GPU_DIR)/.rows | wc -l) in $(GPU_DIR)"; \
	rm -f $$start $$start.list

# The wheels of MuJoCo and its Python dependencies for the device's image (Python 3.12,
# manylinux x86_64), at the versions of this lock, into .whl/ (ignored; carried by a device call).
GPU_WHEEL_PYTHON ?= 3.12
gpu-wheels: $(STAMP)
	@grep -qs '^/.whl/' $$(git rev-parse --git-dir)/info/exclude || \
		{ mkdir -p $$(git rev-parse --git-dir)/info; echo /.whl/ >> $$(git rev-parse --git-dir)/info/exclude; }
	$(PY) -m pip download -q --no-deps --only-binary=:all: --python-version $(GPU_WHEEL_PYTHON) \
		--implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 \
		--platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 -d .whl \
		$$($(PY) -m pip list --format=freeze 2>/dev/null | grep -iE '^(mujoco|mujoco-core|gymnasium|glfw|imageio|cloudpickle|farama-notifications)==')
	@ls .whl

# Tables, figures and report of the campaign's stored rows (before committing them).
paper-core-report: $(STAMP)
	$(PY) -m bench --results $(CAMPAIGN_DIR) figures
	$(PY) -m bench --results $(CAMPAIGN_DIR) report
	$(PY) -m bench.findings

clean:
	rm -rf $(VENV) .cache .pytest_cache
