# skyscatter: `make run` renders the default scenes into out/, `make test` runs the tests.
# `make run` installs the package alone (`pip install -e .`: its default scenes write PNG, EXR
# and a GIF, no MP4); `make test` adds the [test] extras. Each has its stamp, so `make run`
# then `make test` installs the test extras once.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
TEST_STAMP := $(VENV)/.installed-test

# Debian's chromium for the viewer's browser tests, zsh and fish for the shell-completion tests,
# glslang for the exported HLSL
# (root, or sudo when not root)
SUDO   := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
APT    := $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get

.PHONY: run test lint bench clean test-tools

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e .
	$(BIN)/skyscatter compile
	touch $(STAMP)

$(TEST_STAMP): $(STAMP)
	$(BIN)/pip install --quiet -e ".[test]"
	touch $(TEST_STAMP)

run: $(STAMP)
	$(BIN)/python scripts/render_defaults.py out

# command:package; glslang's HLSL front end compiles the exported tables' HLSL
# (tests/viewer/test_table_export.py)
TEST_TOOLS := chromium:chromium zsh:zsh fish:fish glslangValidator:glslang-tools
test-tools:
	@missing=$$(for t in $(TEST_TOOLS); do command -v $${t%%:*} >/dev/null 2>&1 || echo $${t#*:}; done); \
	if [ -n "$$missing" ]; then echo "installing" $$missing "(apt) for the tests"; \
	  $(APT) install -y -qq $$missing >/dev/null 2>&1 || \
	  { $(APT) update -qq && $(APT) install -y -qq $$missing >/dev/null; }; fi

test: $(TEST_STAMP) test-tools
	$(BIN)/ruff check .
	SKYSCATTER_REQUIRE_BROWSER=1 $(BIN)/python -m pytest -q

bench: $(TEST_STAMP)  # bench_viewer drives chromium (playwright)
	$(BIN)/python benchmarks/bench_single_scattering.py
	$(BIN)/python benchmarks/bench_tables.py
	$(BIN)/python benchmarks/bench_viewer.py

clean:
	rm -rf $(VENV) out
