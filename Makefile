# Two commands on a fresh machine with only Python and pip:
#   make report   -> creates .venv, installs flexval, builds reports/paper/
#   make test     -> creates/refreshes .venv the same way, runs the test suite
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: report test venv bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip
	$(BIN)/python -m pip install -e ".[test]"
	touch $(STAMP)

# the report also times beam:100 against OpenSeesPy (optional extra); where it cannot be
# installed or loaded, the report's run times say so and everything else is built
PEERS  := $(VENV)/.peers
$(PEERS): $(STAMP)
	$(BIN)/python -m pip install -e ".[test,peers]" || echo "OpenSeesPy not installed"
	touch $(PEERS)

venv: $(STAMP)

report: $(PEERS)
	$(BIN)/flexval info open_chain
	$(BIN)/flexval info closed_chain
	$(BIN)/flexval report --out reports/paper --protocol reports/dynamics/protocol.json --peers

test: $(STAMP)
	$(BIN)/python -m pytest

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_reduced.py
	$(BIN)/python benchmarks/bench_beam_scaling.py
	$(BIN)/python benchmarks/bench_continuum.py
	$(BIN)/python benchmarks/bench_concurrency.py
	$(BIN)/python benchmarks/bench_sweep.py

clean:
	rm -rf $(VENV) .pytest_cache
