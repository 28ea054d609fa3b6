# The two entry points of the README. Both create/reuse .venv first.
VENV   := .venv
PYTHON := $(abspath $(VENV)/bin/python)
MPIEXEC := $(abspath $(VENV)/bin/mpiexec)
BUILD  := build
NP     ?= 2
ARGS   ?=

.PHONY: env demo test clean

env:
	@bash scripts/setup_env.sh

demo: env
	$(MPIEXEC) -n $(NP) $(PYTHON) demos/install.py $(ARGS)

test: env
	$(VENV)/bin/cmake -S . -B $(BUILD) -DPYTHON=$(PYTHON) -DMPIEXEC=$(MPIEXEC) >/dev/null
	cd $(BUILD) && $(abspath $(VENV)/bin/ctest) --output-on-failure --timeout 3600 $(CTEST_ARGS)

clean:
	rm -rf $(BUILD)
