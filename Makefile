# motionblur: `make help` lists the targets.
SHELL := /bin/bash
.DEFAULT_GOAL := help

VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
APT_PACKAGES := libosmesa6 libllvm19 libgl1 libglu1-mesa chromium-headless-shell

# Headless peers: pyrender through OSMesa, Mitsuba's llvm variant through Debian's LLVM 19.
export PYOPENGL_PLATFORM := osmesa
export DRJIT_LIBLLVM_PATH ?= /usr/lib/x86_64-linux-gnu/libLLVM-19.so
export MPLBACKEND := Agg

RUST_SOURCES := $(shell find src -name '*.rs') Cargo.toml Cargo.lock pyproject.toml
EXT_STAMP := $(VENV)/.built
DOCS_STAMP := $(VENV)/.docs-installed

.PHONY: help sysdeps venv build test test-rust test-python fuzz demo bench lint docs fmt notebooks clean

help: ## list the targets
	@grep -hE '^[a-z-]+:.*## ' $(MAKEFILE_LIST) | awk -F':.*## ' '{printf "  make %-12s %s\n", $$1, $$2}'

sysdeps: ## install the Debian packages the peers need (OSMesa, LLVM 19, headless Chromium), when missing
	@missing=""; for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:$$missing"; \
	  SUDO=""; [ "$$(id -u)" = 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing; \
	fi

$(STAMP): requirements-dev.txt
	$(MAKE) sysdeps
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -r requirements-dev.txt
	@# pyrender pins PyOpenGL 3.1.0, whose OSMesa binding is broken; the resolver warning is expected.
	$(PY) -m pip install -q 'pyopengl>=3.1.5' 2>&1 | grep -v 'pyrender 0.1.45 requires PyOpenGL' || true
	touch $@

venv: $(STAMP) ## create the virtualenv with every Python dependency

$(EXT_STAMP): $(STAMP) $(RUST_SOURCES)
	VIRTUAL_ENV=$(abspath $(VENV)) PATH=$(abspath $(VENV))/bin:$$PATH maturin develop --release -q
	touch $@

build: $(EXT_STAMP) ## build the Rust extension (release) into the virtualenv

test-rust: ## cargo test of the pure Rust core
	cargo test --release -q

test-python: build ## pytest, including the notebooks
	$(PY) -m pytest -q -n 2 --nbmake tests notebooks

test: build test-rust test-python ## everything CI runs

FUZZ_EXAMPLES ?= 400
fuzz: build ## the property-based robustness suite with many examples (FUZZ_EXAMPLES per property, random seed)
	MOTIONBLUR_FUZZ=fuzz MOTIONBLUR_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) $(PY) -m pytest -q -n 2 -m robustness tests/robustness

demo: build ## the main job on built-in scenes: images and a speed/error table in out/demo
	$(PY) -m motionblur demo --out out/demo

bench: build ## benchmarks against the peers, measured in the same run (out/bench)
	@all=$$(date +%s); for b in benches/bench_*.py; do echo "== $$b"; t=$$(date +%s); $(PY) $$b || exit 1; \
	  echo "== $$b took $$(( $$(date +%s) - t )) s"; done; echo "== make bench took $$(( $$(date +%s) - all )) s"

lint: build ## cargo fmt, clippy and rustdoc -D warnings, ruff, stubtest, mypy --strict on a user script, extras resolved by pip
	cargo fmt --check
	cargo clippy --release --all-targets -- -D warnings
	cargo clippy --release --features python -- -D warnings
	RUSTDOCFLAGS="-D warnings" cargo doc --no-deps
	RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --features python
	$(VENV)/bin/ruff check python tests benches notebooks
	$(VENV)/bin/ruff format --check python tests benches
	$(PY) -m mypy.stubtest motionblur._core
	@# the public API is typed: a user's script passes mypy --strict (no Any out of a Frame, no untyped call)
	$(PY) -m mypy --strict tests/typing/user_script.py
	@# every extra, and all, resolves with plain pip (metadata only: nothing is built or installed)
	$(PY) -m pip install --dry-run --ignore-installed --quiet ".[all]"

$(DOCS_STAMP): $(STAMP) requirements-docs.txt
	$(PY) -m pip install -q -r requirements-docs.txt
	touch $@

docs: build $(DOCS_STAMP) ## the documentation site in out/site: guide, methods, API from the docstrings, the stored notebooks
	@mkdir -p out
	set -o pipefail; NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict --clean 2>&1 | tee out/docs.log
	@# --strict fails on mkdocs' warnings; this fails on any other warning or error line printed
	@if grep -nE '^(ERROR|WARNING)|ERROR:|Warning:|Traceback' out/docs.log; then \
	  echo "make docs: the build printed the lines above (warnings are errors here)"; exit 1; fi

notebooks: build ## execute the notebooks and store them with their outputs (figures on GitHub and the site)
	$(PY) notebooks/store_outputs.py

fmt: venv ## format Rust and Python in place
	cargo fmt
	$(VENV)/bin/ruff format python tests benches

clean: ## remove build products and outputs
	rm -rf target out $(EXT_STAMP)
