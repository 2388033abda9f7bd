# One-command entry points. See README.md.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: test reproduce errata initial report clean-cache

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

test: $(STAMP)
	$(PY) -m pytest

reproduce: $(STAMP)
	$(PY) -m study reproduce
	$(PY) -m pytest -q -m slow tests/cross_validation
	@echo "report: $(CURDIR)/reports/index.md and $(CURDIR)/reports/report.html"

errata: $(STAMP)
	$(PY) -m study errata

initial: $(STAMP)
	$(PY) -m study initial

report: $(STAMP)
	$(PY) -m study report

clean-cache:
	rm -rf .cache
