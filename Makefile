# All set-up happens here: `make demo` and `make test` work on a fresh Debian machine.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
SUDO   := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
OUT    ?= out

.PHONY: setup llvm demo test lint format bench bench-all docs smoke clean

setup: llvm $(STAMP)

# Dr.Jit needs libLLVM >= 17 (15 and 16 crash it); install Debian's libllvm19 when none is present.
# The search is solas_mi.llvm's own (standard library only), so Makefile and package agree.
llvm:
	@$(PYTHON) -c 'import sys; sys.path.insert(0, "."); from solas_mi.llvm import find_libllvm; sys.exit(find_libllvm()[0] is None)' \
	 || { echo "installing libllvm19 (Dr.Jit needs libLLVM >= 17)"; \
	      $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq libllvm19; }

$(STAMP): pyproject.toml requirements.lock
	@[ -x $(PY) ] || $(PYTHON) -m venv $(VENV) || { \
	   echo "python venv missing: installing python3-venv"; \
	   $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq python3-venv && $(PYTHON) -m venv $(VENV); }
	$(PY) -m pip install -q --disable-pip-version-check -r requirements.lock
	$(PY) -m pip install -q --disable-pip-version-check --no-deps --no-build-isolation -e .
	@touch $(STAMP)

demo: setup
	$(PY) -m solas_mi.demo --out $(OUT)

test: setup
	$(PY) -m pytest -q

# ruff's rules and format (pyproject.toml [tool.ruff]: the rule set, and why each ignored rule is), then mypy on
# the modules that define the public API (.ci/typecheck.py). `make format` rewrites the tree to pass the first two.
lint: setup
	$(PY) -m ruff check .
	$(PY) -m ruff format --check .
	$(PY) .ci/typecheck.py

format: setup
	$(PY) -m ruff check --fix .
	$(PY) -m ruff format .

# `make bench`: the quick set (a few minutes); `make bench-all`: every benchmark (over an hour on 2 cores);
# `make bench BENCH=bench_convolution` runs one. Results land in benchmarks/results/ (the docs include them).
bench: setup
	$(PY) benchmarks/run_all.py $(BENCH)

bench-all: setup
	$(PY) benchmarks/run_all.py --all

# The documentation site in site/: every table of the benchmark and validation pages included from
# benchmarks/results/ (docs/tools/check_pages.py), every example of the README and the site run as
# written (outputs checked where stated; a block not run says why), then `mkdocs build --strict`
# (any warning is an error); the CLI and API reference pages are generated from the code by
# docs/tools/hooks.py at each build (the docstrings' examples run with the pages'), and
# docs/tools/check_reference.py checks that the built site documents every name of solas_mi's and each
# subpackage's __all__, every command, public function and class, and plugin.
docs: setup
	$(PY) docs/tools/check_pages.py
	$(PY) docs/tools/run_examples.py README.md docs
	NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict --site-dir site
	$(PY) docs/tools/check_reference.py site

# The wheel in a fresh environment outside the repository (.ci/smoke.sh)
smoke: setup
	PYTHON=$(PYTHON) bash .ci/smoke.sh

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .ruff_cache .mypy_cache site build
