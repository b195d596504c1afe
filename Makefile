# All set-up happens here: `make demo` and `make test` work on a fresh Debian machine.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
SUDO   := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
OUT    ?= out

.PHONY: setup llvm demo test bench clean

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

bench: setup
	$(PY) benchmarks/run_all.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache
