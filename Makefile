# Each target creates the virtual environment it needs (see README).
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: model test check lint reproduce bench clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

## Derive the model and regenerate generated/ (C, Python, CasADi, MODEL.md).
model: $(STAMP)
	$(PY) -m codegen $(if $(ROBOT),--robot $(ROBOT) --out $(or $(OUT),generated))

## Lint, type-check and run the test suite on both cores (one worker per test file); the
## suite regenerates every robot and fails with the diff if generated/ is stale
## (tests/codegen/test_codegen_cli.py, the same check as `python -m codegen --check`).
test: $(STAMP) lint
	$(PY) -m pytest -q -n 2 --dist loadfile

lint: $(STAMP)
	$(VENV)/bin/ruff check modeling codegen runtime tests
	$(VENV)/bin/mypy

reproduce: $(STAMP)
	$(PY) -m runtime reproduce --out docs/reproduction --compare-plant mujoco

## Benchmarks and firmware reports; checks the Cortex-M4 cross-compiler first, so that a
## missing one fails before BENCHMARKS.md is rewritten.
bench: $(STAMP)
	@command -v arm-none-eabi-gcc >/dev/null 2>&1 || { echo "make bench: arm-none-eabi-gcc not found (apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi, as .ci/run does)" >&2; exit 2; }
	$(PY) -m runtime bench
	$(PY) -m runtime.tooling.firmware.report
	$(PY) -m runtime.tooling.firmware.compare_casadi

clean:
	rm -rf build out reproduction .pytest_cache .mypy_cache .ruff_cache
