# satagraph: `make demo` runs the main job on a built-in example, `make test` runs the tests.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: venv test test-slow demo bench scatter sweep clean

$(STAMP): setup.cfg pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q torch==2.13.0
	$(PY) -m pip install -q -e '.[dev]'
	touch $(STAMP)

venv: $(STAMP)

# pytest keeps the test modules it rewrote for assert messages (and Python its
# bytecode) only where bytecode may be written: a shell that sets
# PYTHONDONTWRITEBYTECODE would compile every module again in each worker and run
# (4 s of a 2-core run), so the tests allow it.
TEST_ENV := PYTHONDONTWRITEBYTECODE=

test: $(STAMP)
	$(TEST_ENV) $(PY) -m pytest -q -n 2 tests

# Only the tests marked slow (every real file, real training runs, kill -9
# and resume, ddp_spawn, the sweep end to end); CI runs it after `make test`.
test-slow: $(STAMP)
	$(TEST_ENV) $(PY) -m pytest -q -n 2 -m slow tests

# The whole pipeline on the procedural zoo in under 10 minutes on a CPU (zoo,
# training, retargeting, rendering into demo_output/), e.g.
# make demo DEMO_ARGS="--minutes 2 --output /tmp/demo" or DEMO_ARGS=--quick.
DEMO_ARGS ?=
demo: $(STAMP)
	$(VENV)/bin/satagraph demo $(DEMO_ARGS)

# The optional torch-scatter accelerator (the 'scatter' extra; no wheel here,
# it builds from source in 5-10 minutes). benchmarks/compile_step.py measures
# the training step with and without it; a failed build leaves it without.
SCATTER_STAMP := $(VENV)/.scatter
$(SCATTER_STAMP): $(STAMP)
	$(PY) -m pip install -q --no-build-isolation 'torch-scatter==2.1.2' || \
		echo "torch-scatter did not build: compile_step.py measures without it only"
	touch $(SCATTER_STAMP)

scatter: $(SCATTER_STAMP)

# Every benchmark writes its table to benchmarks/results/. Run them on an
# otherwise idle machine: on 2 cores a second busy process slows torch's
# thread pool several times over and the ratios stop meaning anything.
bench: $(STAMP) $(SCATTER_STAMP)
	$(PY) benchmarks/pipeline.py
	$(PY) benchmarks/collate.py
	$(PY) benchmarks/semantic_alignment.py
	$(PY) benchmarks/model_cost.py
	$(PY) benchmarks/throughput.py
	$(PY) benchmarks/compile_step.py
	$(PY) benchmarks/scaling.py
	$(PY) benchmarks/compare.py

# The Table-4 ablations and GNN-layer variants, each trained for the same
# budget (SWEEP_MINUTES) on the same data, compared in sweeps/table4/sweep.md.
SWEEP_MINUTES ?= 5
SWEEP_CONFIGS ?= sata_vae ablation_no_gnn ablation_no_spatial_attention ablation_no_temporal \
	ablation_no_fusion ablation_no_text gnn_gin gnn_gat gnn_gatv2 gnn_gcn gnn_transformer
SWEEP_ARGS ?=
sweep: $(STAMP)
	$(VENV)/bin/satagraph sweep --budget $(SWEEP_MINUTES) --output sweeps/table4 \
		$(SWEEP_CONFIGS) $(SWEEP_ARGS)

clean:
	rm -rf $(VENV) build *.egg-info
