# gait_planner: `make run` plans and records a gait, `make test` runs the tests that answer
# in minutes (every test but those marked slow); `make test-slow` runs the slow end-to-end
# ones (long solves, refinements, the web viewer's screenshot); `make test-all` runs both.
# `make fuzz` sends FUZZ_EXAMPLES (1000) hypothesis-drawn requests to a live node
# (test/ros/test_fuzz.py; `make test` runs a seeded 40 of them).
# All set up .venv/ first (tools/setup.sh; quick when nothing changed), which compiles only
# what `make run` plans (walker3d's default problem). `make prepare` builds the rest: every
# ground form and gait of the shipped scenes and their warm-start anchors (about 5 min on 2
# idle cores from an empty compile cache, 14 min under load 3-5; a second once the cache
# marks them prepared); the test targets run it first.

VENV ?= .venv
PYTHON := $(VENV)/bin/python
PYTEST_ARGS ?=
# the tests run on TEST_WORKERS processes (pytest-xdist; 0: in this one): each module's tests
# on one worker, the whole-robot plans one after another on one (test/conftest.py)
TEST_WORKERS ?= 2
PYTEST := $(PYTHON) -m pytest -n $(TEST_WORKERS) --dist loadfile --durations=15
FUZZ_EXAMPLES ?= 1000
PREPARE_SCENES ?= walker3d walker2d compass

.PHONY: setup prepare test test-slow test-all fuzz run docs bench bench-quick bench-peers chromium clean distclean

setup:
	@tools/setup.sh $(VENV)

prepare: setup
	$(VENV)/bin/gait-planner prepare $(PREPARE_SCENES)

test: prepare
	$(PYTEST) test -m "not slow" $(PYTEST_ARGS)

# the tests marked `alone` (re-planned walks charge this machine's wall time; the node's G1
# plan takes half its memory) run after the others, with no test beside them
test-slow: prepare
	$(PYTEST) test -m "slow and not alone" $(PYTEST_ARGS); others=$$?; \
	$(PYTHON) -m pytest test -m "slow and alone" --durations=5 $(PYTEST_ARGS); alone=$$?; \
	exit $$((others || alone))

test-all: test test-slow

fuzz: prepare
	GAIT_PLANNER_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) $(PYTHON) -m pytest test/ros/test_fuzz.py -m fuzz -s --hypothesis-show-statistics $(PYTEST_ARGS)

run: setup
	$(VENV)/bin/gait-planner run

# `docs` plans the default requests again, takes the README's screenshot with Debian's
# chromium (`SCREENSHOT=` keeps the old one) and rewrites every generated number in README.md
# and docs/ from benchmarks/results/*.json (tools/docs.py; 1 to 3 min on 2 cores).
SCREENSHOT ?= --screenshot
docs: prepare chromium
	$(PYTHON) tools/docs.py --plan $(SCREENSHOT)

# Benchmarks (benchmarks/README.md): `bench` rewrites benchmarks/REPORT.md and
# benchmarks/results/*.json (over an hour on 2 cores: work_precision.py ~55 min of it under
# load on 2026-11-27, the plans walked in MuJoCo ~6 min:
# benchmarks/walk.py; robots drafted from their URDF, Bolt and G1, an estimated 15-25 min:
# benchmarks/robots.py); `bench-quick` is a smoke run (~5 min)
# writing to build/bench-quick/ instead.
bench: prepare chromium
	$(PYTHON) benchmarks/bench.py

bench-quick: prepare
	$(PYTHON) benchmarks/bench.py --quick

# `bench-peers` (issues #27, #38): DMOCC against Crocoddyl, Drake and OpenSim Moco, each peer
# in its own env .venv-peers/<peer> (benchmarks/peers/setup_env.sh; a peer whose env cannot
# be made is skipped with the reason), walker2d and walker3d at 4, 8 and 16 intervals per
# phase, 300 s per solve; benchmarks/results/peers.json and benchmarks/peers.png
# (benchmarks/README.md). Every row in one run, one solve at a time, each after the 1-minute
# load average fell to 0.5 (re-run once, then marked, when above); single-threaded
# (PEERS_THREADS=both adds the peers at their libraries' default threads). Run it on an
# idle machine: ~4 h on 2 cores (single; both: ~6.5 h).
PEERS ?= crocoddyl drake opensim
PEERS_THREADS ?= single
PEERS_ARGS ?=
bench-peers: prepare
	@for peer in $(PEERS); do benchmarks/peers/setup_env.sh $$peer || true; done
	$(PYTHON) -m benchmarks.peers.run --peers $(PEERS) --threads $(PEERS_THREADS) $(PEERS_ARGS)

# Debian's chromium takes the pictures of `docs` and `bench` (the README's screenshot,
# benchmarks/robots.png); installed here if missing, and without it they are skipped.
chromium:
	@command -v chromium >/dev/null || { echo "installing Debian's chromium for screenshots"; \
	  apt-get install -y --no-install-recommends chromium >/dev/null \
	  || echo "chromium could not be installed: pictures are skipped"; }

# Build outputs and caches; keeps .venv/ (and forgets its msg_defs build, so the next
# `make setup` rebuilds and reinstalls gait_planner_msgs) and keeps runs/.
clean:
	rm -rf build install log .pytest_cache .hypothesis *.egg-info
	rm -rf $(VENV)/.gait_planner_setup/build $(VENV)/.gait_planner_setup/msg_defs
	find . -path ./$(VENV) -prune -o -name __pycache__ -type d -prune -exec rm -rf {} +

# Everything `make setup` created, the virtual environment included.
distclean: clean
	rm -rf $(VENV)
