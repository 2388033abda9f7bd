# One-command entry points. See README.md.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
# sympy's simplification (errata table, derivation) takes paths that depend on Python's hash order;
# a fixed seed makes its run time and output the same on every run.
export PYTHONHASHSEED := 0

.PHONY: test reproduce verify emulate run errata initial report bench browser check-report clean-cache lock

# Exact versions from requirements.lock, then the package itself without resolving anything again.
$(STAMP): requirements.lock pyproject.toml setup.py
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.lock
	$(PY) -m pip install --quiet --no-deps -e .
	touch $(STAMP)

test: $(STAMP)
	$(PY) -m pytest

# Every study (cached cases are reused), then the report. Fails if a case fails that its case list does not
# expect to fail, if a friction run breaks its energy balance (tables/energy_balance.csv), or if the report cannot
# be built; what the checks find is written into the report.
# WORKERS=N sets the local worker processes; SCHEDULER=tcp://host:8786 runs the cases on a Dask cluster.
reproduce: $(STAMP)
	$(PY) -m study reproduce $(if $(WORKERS),--workers $(WORKERS)) $(if $(SCHEDULER),--scheduler $(SCHEDULER))

# The reproducibility check: the slow tests (long cross-validation runs, the browser check when Chromium is there),
# every table regenerated and compared with the snapshot in reports/tables by the rules of reference/verify.toml,
# then every in-house case rerun from a state moved by +-4 ulps (reports/tables/perturbation_check.csv).
verify: $(STAMP)
	$(PY) -m pytest -m slow
	$(PY) -m study verify $(if $(WORKERS),--workers $(WORKERS)) $(if $(OUT),--out $(OUT))
	$(PY) -m study verify --perturb $(if $(WORKERS),--workers $(WORKERS)) $(if $(OUT),--out $(OUT))

# Other hosts emulated on this one: the fast tests, the slow tests and `study verify` under other floating-point
# code paths (numba's target CPU, NumPy's dispatched kernels, OpenBLAS's core type), each with a cache of its own.
# HOSTS=<names> picks configurations from study/emulate.py; TARGETS=<make targets> what runs under each.
emulate: $(STAMP)
	$(PY) -m study.emulate $(if $(HOSTS),--hosts $(HOSTS)) $(if $(TARGETS),--targets $(TARGETS))

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
# screenshots -> reports/screenshots/ (part of the slow tests that `make verify` runs).
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

# Resolve pyproject.toml's ranges again in a new virtual environment and write the exact versions to requirements.lock.
lock:
	rm -rf .lock-venv && $(PYTHON) -m venv .lock-venv
	.lock-venv/bin/python -m pip install --quiet --upgrade pip
	.lock-venv/bin/python -m pip install --quiet '.[test]'
	{ sed -n '/^#/p' requirements.lock; .lock-venv/bin/python -m pip freeze --exclude study; } > requirements.lock.new
	mv requirements.lock.new requirements.lock && rm -rf .lock-venv
