# One-command entry points. See README.md.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
SLOW_PASSED := .cache/slow-tests.passed
# sympy's simplification (errata table, derivation) takes paths that depend on Python's hash order;
# a fixed seed makes its run time and output the same on every run (one random seed once took
# minutes instead of seconds in the errata check).
export PYTHONHASHSEED := 0
SOURCES := $(shell find study tests reference -type f -not -name '*.pyc') pyproject.toml

.PHONY: test reproduce run errata initial report bench browser check-report clean-cache verify

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

test: $(STAMP)
	$(PY) -m pytest

# Every study (cached cases are reused), the report, then the slow cross-validation tests.
# WORKERS=N sets the local worker processes; SCHEDULER=tcp://host:8786 runs the cases on a Dask cluster.
reproduce: $(STAMP)
	$(PY) -m study reproduce $(if $(WORKERS),--workers $(WORKERS)) $(if $(SCHEDULER),--scheduler $(SCHEDULER))
	@$(MAKE) --no-print-directory $(SLOW_PASSED)
	@echo "report: $(CURDIR)/reports/index.md and $(CURDIR)/reports/report.html"

# The slow tests (long cross-validation runs) rerun whenever the code, the tests, the reference
# data or the environment changed since they last passed; otherwise their pass is reused.
$(SLOW_PASSED): $(STAMP) $(SOURCES)
	$(PY) -m pytest -q -m slow
	@mkdir -p $(dir $@) && touch $@

# Regenerate every table and compare it with the snapshot in reports/tables (per-column rules and their reasons:
# reference/verify.toml; prints the worst difference per table; fails on any difference beyond its rule), then the
# conditioning check: every in-house case rerun from a state moved by +-4 ulps (reports/tables/perturbation_check.csv).
# With an empty cache (a fresh clone, or after make clean-cache) every case is computed again.
verify: $(STAMP)
	$(PY) -m study verify $(if $(WORKERS),--workers $(WORKERS))
	$(PY) -m study verify --perturb $(if $(WORKERS),--workers $(WORKERS))

run: $(STAMP)
	$(PY) -m study run $(if $(WORKERS),--workers $(WORKERS)) $(if $(SCHEDULER),--scheduler $(SCHEDULER))

# Accuracy per CPU second, in-house vs Exudyn, measured side by side -> reports/benchmarks/
bench: $(STAMP)
	$(PY) -m study bench

# Headless Chromium for the report's browser check (Debian package; needs the rights to apt-get).
# `make test` and CI do not need it: without it the check is skipped with its reason.
browser:
	@command -v chromium >/dev/null 2>&1 || { apt-get update -qq && apt-get install -y -qq chromium; }

# Open reports/report.html in headless Chromium: images, raw Markdown, math sizes, overflow;
# screenshots -> reports/screenshots/ (part of the slow tests that `make reproduce` runs).
check-report: $(STAMP)
	$(PY) -m pytest -q -m slow -k browser

errata: $(STAMP)
	$(PY) -m study errata

initial: $(STAMP)
	$(PY) -m study initial

report: $(STAMP)
	$(PY) -m study report

clean-cache:
	rm -rf .cache
