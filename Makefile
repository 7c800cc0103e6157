# Quickstart: `make demo` and `make test` each set up .venv from nothing and run.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint setup clean sounds schema conformance baselines bench bench-quick fuzz editor-tools
# npm packages used by tests (the editor schema's language-server test), kept outside the repository
NPM_PREFIX ?= $(or $(XDG_CACHE_HOME),$(HOME)/.cache)/physics-scenarios/npm
YAML_LANGUAGE_SERVER := yaml-language-server@1.25.0

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q -e '.[all,dev,ray]'
	touch $(STAMP)

setup: $(STAMP)

demo: $(STAMP)
	$(BIN)/scenario run scenarios/factory_physics.yaml --all-variants --out traces/demo --force
	$(BIN)/scenario compare scenarios/factory_physics.yaml --all-variants --out traces/compare; \
	status=$$?; echo "Comparison report: file://$(CURDIR)/traces/compare/report.html"; exit $$status

test: $(STAMP)
	$(BIN)/python -m pytest -q

lint: $(STAMP)
	$(BIN)/ruff check runner backends reports tests bench
	$(BIN)/mypy

sounds: $(STAMP)
	$(BIN)/python scenarios/sounds/make_sounds.py

schema: $(STAMP)
	$(BIN)/scenario schema > runner/schema/scenario.schema.json

conformance: $(STAMP)
	$(BIN)/scenario conformance --out traces/conformance --markdown docs/conformance.md

baselines: $(STAMP)
	$(BIN)/scenario baseline scenarios/*.yaml --backend pybullet,mujoco,dart,ode --baseline baselines

fuzz: $(STAMP)
	FUZZ_CASES=20000 FUZZ_STRUCTURED=20000 FUZZ_FAULTS=200 $(BIN)/python -m pytest -q -p no:cacheprovider tests/reliability

editor-tools:
	mkdir -p $(NPM_PREFIX)
	npm install --prefix $(NPM_PREFIX) --no-audit --no-fund --no-save $(YAML_LANGUAGE_SERVER)

bench: $(STAMP)
	$(BIN)/python -m bench

bench-quick: $(STAMP)
	$(BIN)/python -m bench --quick --out traces/bench-quick.md

clean:
	rm -rf $(VENV) traces .pytest_cache
