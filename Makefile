# Two commands on a fresh machine:
#   make demo   set up .venv (torch CPU wheel first) and run a teaching episode
#   make test   set up .venv, then run the linter (ruff), the type checker (mypy, on learning/) and the tests
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.teachbot-installed

.PHONY: demo test lint clean experiments readme-tables

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet torch==2.13.0
	$(PY) -m pip install --quiet -e '.[dev,ray,rl]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/teachbot demo --seed 0 --turns 30 --budget 40 --change-every 5 --strategy dt-task

# pytest runs on every core (pytest-xdist; TEST_WORKERS=0 for one process), idle workers taking queued tests
# from busy ones.
TEST_WORKERS ?= auto

test: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy
	$(PY) -m pytest -n $(TEST_WORKERS) --dist worksteal --durations=25; status=$$?; \
	if [ $$status -eq 5 ]; then echo "pytest collected no tests: that is a failure here"; exit 1; fi; \
	exit $$status

clean:
	rm -rf $(VENV) runs .pytest_cache .ruff_cache .mypy_cache

# Rerun every suite the docs cite (docs/experiments.toml) and rewrite every results table in
# docs/experiments.md and the README from that run, each stamped with the commit and command.
experiments: $(STAMP)
	$(PY) scripts/experiments.py

# Only the README's demo and study tables (docs/readme-tables.toml; a few minutes): play their teachbot demo
# and study commands, rewrite the summary:demo and summary:study blocks wherever README.md has their markers,
# retake the study figure and record the checked transcripts' hashes that tests/dialog/test_readme_tables.py
# replays (docs/readme-tables-record.json). The demo's options there are the ones `make demo` runs.
readme-tables: $(STAMP)
	$(PY) scripts/experiments.py --suites readme
