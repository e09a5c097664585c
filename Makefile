# Two commands on a fresh machine:
#   make demo   set up .venv (torch CPU wheel first) and run a teaching episode
#   make test   set up .venv, then run the linter (ruff), the type checker (mypy, on learning/) and the tests
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.teachbot-installed

.PHONY: demo test lint clean experiments

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet torch==2.13.0
	$(PY) -m pip install --quiet -e '.[dev,ray,rl]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/teachbot demo --seed 0 --turns 30 --budget 40 --change-every 5 --strategy dt-task

test: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy
	$(PY) -m pytest --durations=25; status=$$?; \
	if [ $$status -eq 5 ]; then echo "pytest collected no tests: that is a failure here"; exit 1; fi; \
	exit $$status

clean:
	rm -rf $(VENV) runs .pytest_cache .ruff_cache .mypy_cache

# Rerun every suite the docs cite (docs/experiments.toml) and rewrite every results table in
# docs/experiments.md and the README from that run, each stamped with the commit and command.
experiments: $(STAMP)
	$(PY) scripts/experiments.py
