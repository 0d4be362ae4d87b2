# skyscatter: `make run` renders the default scenes into out/, `make test` runs the tests.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

# Debian's chromium for the viewer's browser tests (root, or sudo when not root)
SUDO   := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
APT    := $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get

.PHONY: run test lint bench clean chromium glslang

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e ".[test]"
	$(BIN)/skyscatter compile
	touch $(STAMP)

run: $(STAMP)
	$(BIN)/python scripts/render_defaults.py out

chromium:
	@command -v chromium >/dev/null 2>&1 || { echo "installing chromium (apt) for the viewer tests"; \
	  $(APT) install -y -qq chromium >/dev/null 2>&1 || \
	  { $(APT) update -qq && $(APT) install -y -qq chromium >/dev/null; }; }

# glslang's HLSL front end compiles the exported tables' HLSL (tests/viewer/test_table_export.py;
# skipped without it)
glslang:
	@command -v glslangValidator >/dev/null 2>&1 || { echo "installing glslang-tools (apt)"; \
	  $(APT) install -y -qq glslang-tools >/dev/null 2>&1 || \
	  { $(APT) update -qq && $(APT) install -y -qq glslang-tools >/dev/null; } || true; }

test: $(STAMP) chromium glslang
	$(BIN)/ruff check .
	SKYSCATTER_REQUIRE_BROWSER=1 $(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_single_scattering.py
	$(BIN)/python benchmarks/bench_tables.py
	$(BIN)/python benchmarks/bench_viewer.py

clean:
	rm -rf $(VENV) out
