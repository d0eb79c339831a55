# Two commands on a fresh machine: `make run` and `make test`. Both create .venv first.
# `make run` installs the package alone (what running needs); `make test` adds the test,
# plot and benchmark extras and the example plugins under plugins/. `make lint` needs only
# ruff and `make typecheck` only the dev extra (CONTRIBUTING.md), not playwright or the
# benchmark's peers.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
PIP := $(BIN)/python -m pip --quiet --disable-pip-version-check
RUN_STAMP := $(VENV)/.installed-run
STAMP := $(VENV)/.installed
LINT_STAMP := $(VENV)/.installed-lint
DEV_STAMP := $(VENV)/.installed-dev
EXTRAS ?= test,plot,bench,cluster,monitor,browser-test

.PHONY: run test wheel-check sdist-check lint typecheck bench icount routines coverage golden venv clean monitor-screenshots reliability

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(RUN_STAMP): pyproject.toml | $(BIN)/python
	$(PIP) install -e .
	touch $(RUN_STAMP)

$(STAMP): pyproject.toml $(RUN_STAMP)
	$(PIP) install -e ".[$(EXTRAS)]"
	@for p in plugins/*/; do [ -f "$$p/pyproject.toml" ] && $(PIP) install -e "$$p" || true; done
	touch $(STAMP)

# ruff (the lint extra) beside the package's own few dependencies: no extra of a user's
$(LINT_STAMP): pyproject.toml | $(BIN)/python
	$(PIP) install -e ".[lint]"
	touch $(LINT_STAMP)

# what mypy's strict check imports: the dev extra (test, plot, monitor, cluster)
$(DEV_STAMP): pyproject.toml $(RUN_STAMP)
	$(PIP) install -e ".[dev]"
	touch $(DEV_STAMP)

venv: $(STAMP)

# The shipped dock mission, by name, on the built-in simulator, on the virtual clock
# (drop --fast for real time).
RUN_ARGS ?= --fast
run: $(RUN_STAMP)
	$(BIN)/roomba-bt run dock $(RUN_ARGS)

lint: $(LINT_STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check roomba_bt tests bench plugins

typecheck: $(DEV_STAMP)
	$(BIN)/mypy

# pytest names its 15 slowest tests at the end (--durations=15): the suite's budget is 10 min
# on a 2-core CI machine, and the next slow test is seen where it comes in. It runs in
# TEST_WORKERS processes (pytest-xdist), one per core: a test waits on a child, a pty or the
# real clock for much of its time, and one process left the second core idle then. The tests
# are dealt out in order and an idle worker takes the rest of the other's queue
# (--dist worksteal: whole files, --dist loadfile, left one core idle behind the last long
# file, 10:30 against 9:33 on 8112 tests); TEST_WORKERS=0 runs the suite in this one process.
TEST_WORKERS ?= 2
test: $(STAMP) lint typecheck
	$(BIN)/python -m pytest -q -p no:cacheprovider --durations=15 -n $(TEST_WORKERS) --dist worksteal; rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "pytest collected no tests: failing"; exit 1; fi; exit $$rc
	PYTHON=$(PYTHON) .ci/wheel-check
	PYTHON=$(PYTHON) .ci/sdist-check

# What `pip install roomba-bt` gives a new user: the wheel in a fresh venv, in an empty
# directory, lists, validates and runs the shipped missions by name (about a minute).
wheel-check:
	PYTHON=$(PYTHON) .ci/wheel-check

# What a packager gets: the sdist as `python -m build` makes it from the tracked files holds
# every file the tests read and none of a working tree's caches; the wheel built from it
# carries the licence (seconds; docs/releasing.md).
sdist-check:
	PYTHON=$(PYTHON) .ci/sdist-check

bench: $(STAMP)
	$(BIN)/python -m bench

# Instructions per simulator step and per mission tick (callgrind; the machine-independent
# companion of the timings in docs/performance.md; 1 to 3 min on 2 cores).
icount: $(STAMP)
	$(BIN)/python -m bench.icount

# docs/reliability.md's figures: noise on the virtual clock, the fault table over a pty, memory
# over 4 robot-hours (about 40 min of CPU, and real time for the faults).
reliability: $(STAMP)
	$(BIN)/python -m bench.reliability

# The routines' success rates and speed into docs/routines.md (2 to 7 min on 2 cores).
routines: $(STAMP)
	$(BIN)/python -m roomba_bt.evaluate.report --docs docs --missions missions

# clean.yaml against the firmware's Clean into docs/routines.md (about 5 min on this 2-core VM, session 22).
coverage: $(STAMP)
	$(BIN)/python -m roomba_bt.evaluate.coverage_report --docs docs --missions missions --runs 50 --apartment-runs 4 --drift-runs 20 --jobs 2

# The monitor page's pictures in docs/monitor.md (a dock run in the apartment, mid-approach;
# needs the OS's chromium: apt-get install chromium).
monitor-screenshots: $(STAMP)
	$(BIN)/python -m bench.monitor_screenshots

clean:
	rm -rf $(VENV) build *.egg-info

# Renew the golden recordings of the simulator's bytes (tests/golden): only when a change of
# bytes is intended, and say why in the commit.
golden: $(STAMP)
	$(BIN)/python tests/golden/scenarios.py --renew
