# Two commands on a fresh machine with only Python and pip:
#   make report   -> creates .venv, installs flexval, builds reports/paper/, reports/flexures/
#                    and reports/mechanisms/
#                    (their run times into build/timings/: a clean checkout stays clean)
#   make test     -> creates/refreshes .venv the same way, lints (ruff), runs the test suite
#   make docs     -> the documentation site in site/ (strict: a warning fails it)
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: report timings test lint venv bench docs clean

# the install ends by compiling, into numba's on-disk cache, the kernels a two-level path of
# each reduced family calls, so that later commands load them; a kernel no such path calls
# (a batch's, an indefinite tangent's) is compiled where a later command first calls it
WARM = run open_chain --model beam:20 --model dcmm:2 --model prbm --model ee --load-case f+ --levels 2

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip
	$(BIN)/python -m pip install -e ".[test]"
	$(BIN)/flexval $(WARM) > /dev/null
	touch $(STAMP)

# the report also times beam:100 against OpenSeesPy (optional extra); where it cannot be
# installed or loaded, the report's run times say so and everything else is built
PEERS  := $(VENV)/.peers
$(PEERS): $(STAMP)
	$(BIN)/python -m pip install -e ".[test,peers]" || echo "OpenSeesPy not installed"
	touch $(PEERS)

# the documentation site's tools (optional extra [docs])
DOCS   := $(VENV)/.docs
$(DOCS): $(STAMP)
	$(BIN)/python -m pip install -e ".[test,docs]"
	touch $(DOCS)

venv: $(STAMP)

PAPER_REPORT = --out reports/paper --protocol reports/dynamics/protocol.json --threed reports/threed/threed.json --peers
FLEXURE_REPORT = notch_fourbar filleted_stage tapered_leaf spline_flexure --out reports/flexures
MECHANISM_REPORT = parallel_guide folded_guide cross_pivot cartwheel_hinge trapezoid_pivot
MECHANISM_REPORT += bistable_truss bridge_amplifier --out reports/mechanisms
# where `make report` writes the run times it measures (ignored by git)
TIMINGS = build/timings

report: $(PEERS)
	$(BIN)/flexval info open_chain
	$(BIN)/flexval info closed_chain
	$(BIN)/flexval report $(PAPER_REPORT) --timings $(TIMINGS)/paper
	$(BIN)/flexval report $(FLEXURE_REPORT) --timings $(TIMINGS)/flexures
	$(BIN)/flexval report $(MECHANISM_REPORT) --timings $(TIMINGS)/mechanisms

# the committed run times beside the reports (machine-dependent: refreshed deliberately,
# never by `make report`, which leaves a clean checkout clean)
timings: $(PEERS)
	$(BIN)/flexval report $(PAPER_REPORT)
	$(BIN)/flexval report $(FLEXURE_REPORT)
	$(BIN)/flexval report $(MECHANISM_REPORT)

# lint and format check first (ruff, configured in pyproject.toml), then the suite
test: lint
	$(BIN)/python -m pytest

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

# strict: a warning (a broken link, a docstring griffe cannot read) fails the build;
# then the built pages are checked for every scene field, CLI command and key API name
docs: $(DOCS)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict -f docs/mkdocs.yml
	$(BIN)/python docs/check_site.py site

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_reduced.py
	$(BIN)/python benchmarks/bench_beam_scaling.py
	$(BIN)/python benchmarks/bench_continuum.py
	$(BIN)/python benchmarks/bench_concurrency.py
	$(BIN)/python benchmarks/bench_sweep.py

clean:
	rm -rf $(VENV) .pytest_cache site
