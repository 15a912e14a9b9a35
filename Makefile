# g2tom: every target bootstraps .venv by itself.
#   make run                      the paper's full study on the default scenario
#   make test                     the test suite
#   make run SCENARIO=published   a bundled scenario by name, or SCENARIO=path/to/file.toml
#   make cube DATA=out SET="oxide.n_realizations=100 cube.weights=area"
PYTHON   ?= python3
VENV     := .venv
G2TOM    := $(VENV)/bin/g2tom
SCENARIO ?= paper
DATA     ?= data
SET      ?=
# SET is split at spaces; `g2tom` glues back a value split inside brackets or quotes, so
# SET="oxide.xi=[0.3, 0.5] cube.weights=area" works.
ARGS     := --config $(SCENARIO) --data-dir $(DATA) $(foreach s,$(SET),--set '$(s)')
SOURCES  := $(shell find pipeline -name '*.py' -o -name '*.toml')
ANALYSIS := $(shell find analysis -name '*.py')
STAMPS   := $(DATA)/.stamps
# Independent targets run side by side (the physics benchmarks beside the study's stages: `make run`
# in 0.82 of the time of one at a time on two cores); JOBS=1 runs them one at a time.
JOBS     ?= 2
MAKEFLAGS += --jobs=$(JOBS)
# Every target's Python caches its compiled modules (__pycache__, ignored by git) even where the
# environment says not to: each g2tom process otherwise compiles the package again, and pytest
# rewrites every test file's asserts again in each worker (collection 7.4 s instead of 3.3 s).
unexport PYTHONDONTWRITEBYTECODE

.PHONY: all run test stress test-gpu bench compare figures report contact oxide cube fits surrogate params validate atlas atlas-plan run-check docs clean FORCE
all: run

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/pip install --quiet --upgrade pip
	$(VENV)/bin/pip install --quiet -e '.[test,reference]'
	touch $@

# The stamps are rewritten only when a stage's parameters change, so make re-runs a stage
# exactly when its configuration, its inputs or the code changed. `g2tom stamp` also touches
# the stamp of a stage file that is unreadable (truncated, damaged) or was built from another
# configuration (`g2tom fits --set ...`), so make rebuilds it instead of failing on it.
STAMP_FILES := $(foreach s,contact oxide cube fits surrogate,$(STAMPS)/$(s).json)
$(STAMP_FILES) &: FORCE | $(VENV)/.installed
	@$(G2TOM) stamp $(ARGS)
FORCE:

$(DATA)/contact.nc: $(STAMPS)/contact.json $(SOURCES) | $(VENV)/.installed
	$(G2TOM) contact $(ARGS)
$(DATA)/oxide.nc: $(STAMPS)/oxide.json $(SOURCES) | $(VENV)/.installed
	$(G2TOM) oxide $(ARGS)
$(DATA)/cube.nc: $(STAMPS)/cube.json $(DATA)/contact.nc $(DATA)/oxide.nc $(SOURCES) | $(VENV)/.installed
	$(G2TOM) cube $(ARGS)
$(DATA)/fits.nc: $(STAMPS)/fits.json $(DATA)/cube.nc $(SOURCES) | $(VENV)/.installed
	$(G2TOM) fits $(ARGS)
$(DATA)/surrogate.nc: $(STAMPS)/surrogate.json $(DATA)/fits.nc $(SOURCES) | $(VENV)/.installed
	$(G2TOM) surrogate $(ARGS)

contact: $(DATA)/contact.nc
oxide: $(DATA)/oxide.nc
cube: $(DATA)/cube.nc
fits: $(DATA)/fits.nc
surrogate: $(DATA)/surrogate.nc

# The physics benchmarks the report shows: Barber's check of every spot discretization (drawn in a
# figure) and the chain of biases from the published conventions (a section of the report; about
# 15 s of two cores). The chain reads the contact it shares with the scenario from contact.nc, the
# numbers solving it gives, and a new contact.nc does not make it stale. It runs after the cube (order
# only): beside the single-threaded fits, surrogate and figures rather than beside the cube, which
# takes both cores (on two cores `make run` takes about 5 s less so).
$(DATA)/bench/spots.json: $(STAMPS)/contact.json $(STAMPS)/cube.json $(SOURCES) | $(VENV)/.installed
	$(G2TOM) bench $(ARGS) --only spots
$(DATA)/bench/biases.json: $(SOURCES) | $(VENV)/.installed $(DATA)/contact.nc $(DATA)/cube.nc
	$(G2TOM) bench $(ARGS) --only biases

# The figures in two commands: the results' family once the surrogate is written, the others (the
# contact, the oxide fields, Barber's check, the comparison and the validation, which draw no
# later stage) as soon as their inputs are, beside the cube.
FIGURE_GROUPS := $(DATA)/figures/.results $(DATA)/figures/.others
$(DATA)/figures/.results: $(DATA)/surrogate.nc $(ANALYSIS) $(SOURCES) | $(VENV)/.installed
	$(G2TOM) figures $(ARGS) --only results
	touch $@
$(DATA)/figures/.others: $(DATA)/contact.nc $(DATA)/oxide.nc $(DATA)/bench/spots.json $(ANALYSIS) $(SOURCES) $(wildcard $(DATA)/compare/*/fits.nc) | $(VENV)/.installed
	$(G2TOM) figures $(ARGS) --only contact --only oxide --only point --only barber --only validate
	touch $@
$(DATA)/figures/.written: $(FIGURE_GROUPS)
	touch $@
$(DATA)/report.md: $(DATA)/figures/.written $(DATA)/bench/biases.json $(wildcard $(DATA)/bench/*.json) | $(VENV)/.installed
	$(G2TOM) report $(ARGS)

figures: $(DATA)/figures/.written
report: $(DATA)/report.md
# The checks of a whole run (e.g. a (xi, lambda) grid too small for the surrogate) before the first stage.
run-check: | $(VENV)/.installed
	$(G2TOM) run --check $(ARGS)
run: run-check report

# Greenwood's closed form against the exact point-interaction model on one modest ensemble
# (both under $(DATA)/compare/<model>); `make report` includes the comparison when present.
COMPARE_N ?= 30
compare: | $(VENV)/.installed
	for m in greenwood point; do for s in contact oxide cube fits surrogate; do \
	  $(G2TOM) $$s --config $(SCENARIO) --data-dir $(DATA)/compare/$$m $(foreach s,$(SET),--set $(s)) \
	    --set oxide.n_realizations=$(COMPARE_N) --set cube.model=$$m || exit 1; done; done

# The chain on every scene of the atlas's design over (mu, Pi) (pipeline/atlas/run.py): the plan first,
# then one scene per core; a killed atlas continues with the scenes not written yet.
# Its base scene is the bundled scenario `atlas` (5 xi x 6 lambda, 5 % target): ATLAS_SCENARIO=... to change.
ATLAS_SCENARIO ?= atlas
ATLAS_ARGS := --config $(ATLAS_SCENARIO) --data-dir $(DATA) $(foreach s,$(SET),--set '$(s)')
atlas-plan: | $(VENV)/.installed
	$(G2TOM) plan --atlas $(ATLAS_ARGS)
# ... and ships its surrogate in the package (pipeline/atlas_surrogate.json: commit and config hash inside).
atlas: atlas-plan | $(VENV)/.installed
	$(G2TOM) atlas $(ATLAS_ARGS)
	cp $(DATA)/atlas/surrogate.json pipeline/atlas_surrogate.json

bench: | $(VENV)/.installed
	$(G2TOM) bench $(ARGS) --verbose

# The full-field reference against g2tom (g2tom's own solver; VALIDATE="--solver tamaas" for
# tamaas', the `reference` extra installed here); not part of `make run`.
# VALIDATE="--quick" for the 256^2 check (a few minutes at most).
VALIDATE ?=
validate: | $(VENV)/.installed
	$(VENV)/bin/pip install --quiet -e '.[reference]'
	$(G2TOM) validate --data-dir $(DATA) $(VALIDATE)
	$(G2TOM) validate --data-dir $(DATA) --surface random_process $(VALIDATE)

params: | $(VENV)/.installed
	$(G2TOM) params $(ARGS)

# One pytest worker per core (pytest-xdist); a test file stays on one worker, in order (some
# modules' tests build on their module's earlier ones). `.venv/bin/python -m pytest` runs serially.
test: | $(VENV)/.installed
	$(VENV)/bin/python -m pytest -n auto --dist loadfile

# The reference's GPU path (pytest marker `gpu`) and its benchmark: CuPy and a GPU needed
# (`pip install -e '.[gpu]'`, never by make); elsewhere the tests skip and the bench says why.
test-gpu: | $(VENV)/.installed
	$(VENV)/bin/python -m pytest -m gpu -rs tests/test_reference_fft.py tests/test_reference_capped.py tests/test_surface.py
	$(G2TOM) bench --only gpu --only surface_gpu --verbose

# Long sweeps (pytest marker `stress`, in any test file; a fast variant of each runs in `make test`).
stress: | $(VENV)/.installed
	$(VENV)/bin/python -m pytest -n auto --dist loadfile -m stress

# The documentation (docs/, Sphinx with the `docs` extra) into docs/_build/html; warnings are errors.
docs: | $(VENV)/.installed
	$(VENV)/bin/pip install --quiet -e '.[docs]'
	$(VENV)/bin/sphinx-build -W --keep-going -b html docs docs/_build/html

# Also the temporaries (.<name>.*.tmp) an interrupted (SIGKILLed) write leaves behind.
clean:
	rm -rf $(DATA)/*.nc $(DATA)/figures $(DATA)/bench $(DATA)/report.* $(DATA)/table3.* $(DATA)/timings.json $(STAMPS)
	rm -f $(DATA)/.*.tmp
