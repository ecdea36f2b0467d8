# c1surf: two set-up commands, `make demo` and `make test`; each builds .venv itself.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
OUT    := out
DEMO_MESH := sample_meshes/twisted.obj

.PHONY: demo test bench golden clean fuzz

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# One stamp per set of extras, remade whenever pyproject.toml changes.
$(VENV)/.stamp-base: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e .
	touch $@

$(VENV)/.stamp-test: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $@

$(VENV)/.stamp-bench: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[test,bench]'
	touch $@

# The whole job on one sample mesh: tessellation, JSON and IGES patch files, an EXR curvature
# image with its PNG preview and reflection lines, then the G1 check and the exact measures.
demo: $(VENV)/.stamp-base
	mkdir -p $(OUT)
	$(BIN)/c1surf convert $(DEMO_MESH) -o $(OUT)/twisted.ply --patches $(OUT)/twisted.json --patches $(OUT)/twisted.igs
	$(BIN)/c1surf render $(OUT)/twisted.json -o $(OUT)/twisted.exr --png $(OUT)/twisted.png --zebra $(OUT)/twisted_zebra.png
	$(BIN)/c1surf check $(OUT)/twisted.json
	$(BIN)/c1surf measure $(OUT)/twisted.json

test: $(VENV)/.stamp-test
	$(BIN)/lint-imports
	$(BIN)/python -m pytest -q -n auto

# The long run of the mutation fuzzer (issue 42; `make test` runs cases 0-239): FUZZ_CASES cases from FUZZ_START,
# two worker processes; the result in fuzz-report.json (docs/hostile-input.md has the last one).
FUZZ_CASES ?= 20000
FUZZ_START ?= 100000
fuzz: $(VENV)/.stamp-test
	nice -n 10 $(BIN)/python tests/hostile/fuzzing.py --cases $(FUZZ_CASES) --start $(FUZZ_START) --jobs 2 --report fuzz-report.json

bench: $(VENV)/.stamp-bench
	$(BIN)/python bench/run.py

# Reference outputs of the sample meshes for tests/test_golden.py; rerun after an intended change.
golden: $(VENV)/.stamp-base
	$(BIN)/python tests/golden/regenerate.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache
