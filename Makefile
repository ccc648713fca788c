# gait_planner: `make run` plans and records a gait, `make test` runs the tests.
# Both set up .venv/ first (tools/setup.sh; quick when nothing changed).

VENV ?= .venv
PYTHON := $(VENV)/bin/python
PYTEST_ARGS ?=

.PHONY: setup test run clean distclean

setup:
	@tools/setup.sh $(VENV)

test: setup
	$(PYTHON) -m pytest test $(PYTEST_ARGS)

run: setup
	$(VENV)/bin/gait-planner run --compile

# Build outputs and caches; keeps .venv/ (and forgets its msg_defs build, so the next
# `make setup` rebuilds and reinstalls gait_planner_msgs) and keeps runs/.
clean:
	rm -rf build install log .pytest_cache .hypothesis *.egg-info
	rm -rf $(VENV)/.gait_planner_setup/build $(VENV)/.gait_planner_setup/msg_defs
	find . -path ./$(VENV) -prune -o -name __pycache__ -type d -prune -exec rm -rf {} +

# Everything `make setup` created, the virtual environment included.
distclean: clean
	rm -rf $(VENV)
