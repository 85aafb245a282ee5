# The README's two commands: `make repro` (the whole pipeline) and `make test` (the whole test suite).
# Both create .venv with the pinned versions of constraints.txt on first use; nothing else is needed.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

# dvc runs each stage's `python -m ...` from PATH: put the project's environment first
export PATH := $(abspath $(BIN)):$(PATH)
export DVC_NO_ANALYTICS := 1
export MPLBACKEND := Agg

.PHONY: repro test plots lint bench validation-tables wim-site-study clean-venv

$(STAMP): pyproject.toml constraints.txt
	@$(PYTHON) -c 'import sys; assert sys.version_info >= (3, 11), "Python >= 3.11 needed, found " + sys.version' 
	@test -x $(BIN)/python || { echo "make: creating the virtual environment $(VENV)"; $(PYTHON) -m venv $(VENV); }
	@echo "make: upgrading pip"
	@$(BIN)/python -m pip install --quiet --upgrade "pip>=24"
	@echo "make: installing bogie with the pipeline and test dependencies, pinned by constraints.txt (a few minutes" \
	  "on a new machine; pip lists each package as it goes)"
	@{ $(BIN)/python -m pip install --progress-bar off -c constraints.txt -e ".[pipeline,test]" 2>&1; \
	   echo $$? > $(VENV)/.pip-status; } | tee $(VENV)/pip.log | grep --line-buffered -E '^(Collecting|Successfully|ERROR)' ; \
	  status=$$(cat $(VENV)/.pip-status); [ "$$status" = 0 ] || { echo "make: pip failed ($$status); its log: $(VENV)/pip.log"; exit 1; }
	@touch $(STAMP)

# `dvc plots show`'s page template with Vega, Vega-Lite and Vega-Embed inlined from the installed vl-convert-python,
# so that the page opens without internet; .dvc/config's plots.html_template points at it (not committed: 0.9 MB of
# generated JavaScript). `make repro`, `make test` and `make plots` write it, so `dvc plots show` works after any.
PLOTS_TEMPLATE := .dvc/plots.html
$(PLOTS_TEMPLATE): $(STAMP) tools/plots_template.py
	$(BIN)/python tools/plots_template.py $@

repro: $(STAMP) $(PLOTS_TEMPLATE)
	$(BIN)/dvc repro
	$(BIN)/python tools/doc_figures.py  # the figures the README and docs/ quote, from the outputs just made

# the report's plot series (reports/plots/*.csv, dvc.yaml's `plots:`) as dvc_plots/index.html, readable offline
plots: $(STAMP) $(PLOTS_TEMPLATE)
	$(BIN)/dvc plots show

# The report's tests render its pages with poppler's pdftoppm, and the plots page's test opens `dvc plots show`'s page
# in headless Chromium: each installed here when missing and we are root (Debian), otherwise those checks are skipped
# with the reason; a failed install never fails `make test`.
test: $(STAMP) $(PLOTS_TEMPLATE)
	@for need in pdftoppm:poppler-utils chromium:chromium; do \
	  tool=$${need%%:*}; package=$${need#*:}; \
	  command -v $$tool >/dev/null 2>&1 && continue; \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "make test: installing $$package ($$tool) for the report's and the plots page's rendering checks"; \
	    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$package >/dev/null; } \
	      || echo "make test: could not install $$package; the checks that need $$tool will be skipped"; \
	  else \
	    echo "make test: $$tool not found (installing it needs root and apt-get); the checks that need it will be" \
	      "skipped (install $$package, e.g. sudo apt-get install $$package)"; \
	  fi; \
	done
	$(BIN)/python -m pytest

lint: $(STAMP)
	$(BIN)/ruff check bogie pipeline tests bench tools
	$(BIN)/ruff format --check bogie pipeline tests bench tools
	$(BIN)/python tools/numerics_rule.py
	$(BIN)/python tools/conflict_markers.py

bench: $(STAMP)
	$(BIN)/python -m bench

# docs/validation.md's tables from bogie.steel.cases (after any change to the physics); `--check` only compares
validation-tables: $(STAMP)
	$(BIN)/python tools/validation_tables.py

# docs/wim-site.md's table: each part of the WIM site and sensor, one at a time (300 bogies, WIM only, about a minute)
wim-site-study: $(STAMP)
	$(BIN)/python tools/wim_site_study.py

clean-venv:
	rm -rf $(VENV)
