# machsurf_cad: two commands do all the set-up: `make demo` and `make test`.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint format docs bench venv clean np124 workbench-install workbench-uninstall

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	$(BIN)/machsurf demo -o out

test: $(STAMP)
	$(BIN)/python -m pytest -n 2 tests machsurf_cad

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
workbench-install:
	mkdir -p $(FC_MOD)
	ln -sfn $(CURDIR)/workbench $(FC_MOD)/machsurf
	@echo "linked $(FC_MOD)/machsurf -> $(CURDIR)/workbench; restart FreeCAD and pick the machsurf workbench"

workbench-uninstall:
	rm -f $(FC_MOD)/machsurf

clean:
	rm -rf out .pytest_cache build *.egg-info docs/_build docs/generated
