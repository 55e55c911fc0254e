# satagraph: `make demo` runs the main job on a built-in example, `make test` runs the tests.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: venv test demo bench clean

$(STAMP): setup.cfg pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q torch==2.13.0
	$(PY) -m pip install -q -e '.[dev]'
	touch $(STAMP)

venv: $(STAMP)

test: $(STAMP)
	$(PY) -m pytest -q -n 2 tests

# The whole pipeline on the procedural zoo in under 10 minutes on a CPU (zoo,
# training, retargeting, rendering into demo_output/), e.g.
# make demo DEMO_ARGS="--minutes 2 --output /tmp/demo" or DEMO_ARGS=--quick.
DEMO_ARGS ?=
demo: $(STAMP)
	$(VENV)/bin/satagraph demo $(DEMO_ARGS)

bench: $(STAMP)
	$(PY) benchmarks/pipeline.py
	$(PY) benchmarks/collate.py
	$(PY) benchmarks/semantic_alignment.py
	$(PY) benchmarks/model_cost.py

clean:
	rm -rf $(VENV) build *.egg-info
