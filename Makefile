# machsurf_cad: two commands do all the set-up: `make demo` and `make test`.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-slow check lint format docs bench venv clean np124 workbench-install workbench-uninstall

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	$(BIN)/python -m machsurf_cad.threeaxis.compiled
	$(FC_KERNEL)
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	$(BIN)/machsurf demo -o out/demo

# the suite without the slow tier (tests marked slow: the README's examples, real parts, long runs)
test: $(STAMP)
	$(BIN)/python -m pytest -n 2 -m "not slow" tests machsurf_cad

# the slow tier (CI runs it after make test)
test-slow: $(STAMP)
	$(BIN)/python -m pytest -n 2 -m slow tests machsurf_cad

# the numpy core's tests only, for the edit loop (no kernel, no pictures, no FreeCAD)
check: $(STAMP)
	$(BIN)/python -m pytest -n 2 -m "not slow" $(CORE_TESTS)

# ruff (lint and format check) and mypy, configured in pyproject.toml
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

format: $(STAMP)
	$(BIN)/ruff check --fix .
	$(BIN)/ruff format .

# HTML under docs/_build/html; warnings are errors
docs: $(STAMP)
	rm -rf docs/_build docs/generated
	$(BIN)/python -m sphinx -W --keep-going -q -b html docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

bench: $(STAMP)
	$(BIN)/python -m benchmarks

# the numpy core (every test that needs neither the kernel nor pyvista) under FreeCAD's numpy/scipy
CORE_TESTS := tests/test_basis.py tests/test_geometry.py tests/test_builders.py tests/test_deviation.py \
	tests/test_cutters.py tests/test_machining.py tests/test_reff.py tests/test_flank.py tests/test_envelope.py \
	tests/test_layout.py tests/test_core_np124.py tests/test_api.py tests/test_toolpath.py tests/test_verify.py \
	tests/test_simulate.py tests/test_isoscallop.py tests/test_threeaxis.py
np124:
	test -x .venv-np124/bin/python || $(PY) -m venv .venv-np124
	.venv-np124/bin/python -m pip install --quiet "numpy==1.24.4" "scipy==1.10.1" "contourpy<1.4" mpmath pytest
	.venv-np124/bin/python -m pytest -p no:cacheprovider $(CORE_TESTS)

# the FreeCAD add-on, linked into the current user's Mod folder (FreeCAD 0.20+ on Linux)
FC_MOD ?= $(HOME)/.local/share/FreeCAD/Mod
FC_NUMBA ?= $(or $(XDG_CACHE_HOME),$(HOME)/.cache)/machsurf_cad/freecad-numba
# the drop-cutter kernel compiled once for FreeCAD's Python when it has numba (Debian: python3-numba), into the
# cache the add-on (and the FreeCAD tests) read; without FreeCAD or numba nothing happens (the numpy path runs)
FC_KERNEL = -command -v freecadcmd >/dev/null 2>&1 && NUMBA_CACHE_DIR=$(FC_NUMBA) freecadcmd -c "import sys; \
	sys.path.insert(0, '$(CURDIR)'); import runpy; runpy.run_module('machsurf_cad.threeaxis.compiled', \
	run_name='__main__')" < /dev/null
workbench-install:
	mkdir -p $(FC_MOD)
	rm -f $(FC_MOD)/machsurf  # the link of versions before 0.3.0
	ln -sfn $(CURDIR) $(FC_MOD)/machsurf_cad
	@echo "linked $(FC_MOD)/machsurf_cad -> $(CURDIR) (package.xml: workbench/); restart FreeCAD, pick machsurf"
	$(FC_KERNEL)

workbench-uninstall:
	rm -f $(FC_MOD)/machsurf_cad $(FC_MOD)/machsurf

clean:  # build products only: out/ is left alone (it may hold files of yours beside the runs' outputs)
	rm -rf .pytest_cache build *.egg-info docs/_build docs/generated
