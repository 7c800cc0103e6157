# Quickstart: `make demo` and `make test` each set up .venv from nothing and run.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
# tools that are not Python packages of the project (protoc, the Foxglove Studio bundle) live here, outside the repo
CACHE ?= $(or $(XDG_CACHE_HOME),$(HOME)/.cache)/physics-scenarios
FOXGLOVE_STUDIO := $(CACHE)/foxglove-studio

.PHONY: demo test lint setup clean sounds schema conformance baselines bench bench-quick fuzz fuzz-files proto foxglove editor-tools
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

# the two slowest judges (the real Foxglove Studio in Chromium, and the robot-model survey: about 10 minutes
# each on a 2-core machine) run in a second pytest beside the rest, so that both cores work; each prints its
# own summary, and `make test` fails when either does
SLOW_JUDGES := tests/trace/test_foxglove.py tests/integration/test_robot_survey.py

test: $(STAMP)
	@log=$$(mktemp); \
	$(BIN)/python -m pytest -q -p no:cacheprovider $(SLOW_JUDGES) >$$log 2>&1 & judges=$$!; \
	$(BIN)/python -m pytest -q $(addprefix --ignore=,$(SLOW_JUDGES)); rest=$$?; \
	wait $$judges; slow=$$?; \
	echo "== the slow judges, run beside the rest: $(SLOW_JUDGES) (exit $$slow) =="; cat $$log; rm -f $$log; \
	[ $$rest -eq 0 ] && [ $$slow -eq 0 ]

lint: $(STAMP)
	$(BIN)/ruff check runner backends reports tests bench
	$(BIN)/mypy

sounds: $(STAMP)
	$(BIN)/python scenarios/sounds/make_sounds.py

schema: $(STAMP)
	$(BIN)/scenario schema > runner/schema/scenario.schema.json

# mujoco_warp and newton are opt-in (backends/registry.py): named here so that their columns stay in the matrix
conformance: $(STAMP)
	$(BIN)/scenario conformance --backend all,mujoco_warp,newton --out traces/conformance --markdown docs/conformance.md

baselines: $(STAMP)
	$(BIN)/scenario baseline scenarios/*.yaml --backend all --baseline baselines

fuzz: $(STAMP)
	FUZZ_CASES=20000 FUZZ_STRUCTURED=20000 FUZZ_FILES=5000 FUZZ_FAULTS=200 FUZZ_CONCURRENT=20 $(BIN)/python -m pytest -q -p no:cacheprovider tests/reliability

# the 20,000 input files of `make fuzz` alone (model files, WAVs, golden files, traces: 5,000 each)
fuzz-files: $(STAMP)
	FUZZ_FILES=5000 $(BIN)/python -m pytest -q -p no:cacheprovider tests/reliability/test_fuzz_files.py

editor-tools:
	mkdir -p $(NPM_PREFIX)
	npm install --prefix $(NPM_PREFIX) --no-audit --no-fund --no-save $(YAML_LANGUAGE_SERVER)

bench: $(STAMP)
	$(BIN)/python -m bench

bench-quick: $(STAMP)
	$(BIN)/python -m bench --quick --out traces/bench-quick.md

clean:
	rm -rf $(VENV) traces .pytest_cache

# regenerate runner/trace/proto/physics_scenarios_pb2.py(i) from the .proto (protoc 29 from grpcio-tools 1.71, whose
# code runs on protobuf >= 5.29); tests/trace/test_proto.py checks that the two agree
proto:
	test -x $(CACHE)/protoc/bin/python || ($(PYTHON) -m venv $(CACHE)/protoc && $(CACHE)/protoc/bin/pip install -q 'grpcio-tools==1.71.*')
	cd runner/trace/proto && $(CACHE)/protoc/bin/python -m grpc_tools.protoc -I. --python_out=. --pyi_out=. physics_scenarios.proto

# the Foxglove Studio web bundle (npm @foxglove/studio-base 1.48.0 with React 17) for tests/trace/test_foxglove.py;
# needs node and npm; installed outside the repo
foxglove: $(FOXGLOVE_STUDIO)/assets/index.js

$(FOXGLOVE_STUDIO)/assets/index.js:
	rm -rf $(FOXGLOVE_STUDIO) && mkdir -p $(FOXGLOVE_STUDIO)/npm
	cd $(FOXGLOVE_STUDIO)/npm && npm pack --silent @foxglove/studio-base@1.48.0 >/dev/null \
	  && tar -xzf foxglove-studio-base-1.48.0.tgz && rm foxglove-studio-base-1.48.0.tgz \
	  && npm install --silent --no-save --no-audit --no-fund --prefix . react@17.0.2 react-dom@17.0.2 >/dev/null
	cp $(FOXGLOVE_STUDIO)/npm/node_modules/react/umd/react.production.min.js \
	   $(FOXGLOVE_STUDIO)/npm/node_modules/react-dom/umd/react-dom.production.min.js $(FOXGLOVE_STUDIO)/
	ln -sfn npm/package/assets $(FOXGLOVE_STUDIO)/assets
