# luxest pipeline. Every stage is called through a variable so that a researcher can swap one
# for their own program (e.g. `make scenes SCENE_COMPILE=./my-compiler`), as long as it honours
# the contracts in ARCHITECTURE.md.
#
#   make run       the main job on the default scene (cornell-box): compile, path-traced
#                  snapshots + AOVs, local estimate at its sensors, double-local-estimate image
#   make scenes    compile every scene in scenes/ into build/<name>/scene.lxs
#   make test      formatting, lints and all tests
#   make reference noisy   render the generated denoiser dataset (PRESET=quick|full)
#   make validate  local estimate vs exact solutions, direct-simulation baseline
#   make singularity  kernel regularisation at Cornell-box corners (bias, variance vs eps)
#   make train     train the denoiser on that dataset, export models/$(DATASET).onnx
#   make eval      the speed/accuracy trade, the progressive experiment and sensor errors:
#                  reports/summary.md (uses models/$(DATASET).onnx; EVAL_MODEL= to choose)
#   make bench     benchmarks (1M-triangle compile + load, local estimate, image, denoise)

PRESET ?= quick
.DEFAULT_GOAL := run
CARGO ?= cargo
RELEASE := target/release
DEFAULT_SCENE ?= cornell-box

SCENE_COMPILE ?= $(RELEASE)/scene-compile
ESTIMATE ?= $(RELEASE)/estimate
TRACE ?= $(RELEASE)/trace
AOV_WRITE ?= $(RELEASE)/aov-write
DENOISE ?= $(RELEASE)/denoise
EVALUATE ?= $(RELEASE)/evaluate
DEFAULT_MODEL := models/default.onnx

SCENES := $(basename $(notdir $(wildcard scenes/*.ron)))
COMPILED := $(patsubst %,build/%/scene.lxs,$(SCENES))
RUST_SOURCES := $(shell find crates -name '*.rs' -o -name Cargo.toml) Cargo.toml Cargo.lock
MESHES := $(wildcard scenes/meshes/*)

.PHONY: run scenes test lint bench validate singularity clean train pytest eval

include pipelines/dataset.mk

# The main job on the default scene: compile it, path-trace snapshots with their albedo and
# normal features and denoise them (the committed model), estimate illuminance at its sensors
# (local estimate), render its double-local-estimate luminance image with a PNG preview.
run: build/$(DEFAULT_SCENE)/scene.lxs $(ESTIMATE) $(TRACE) $(AOV_WRITE) $(DENOISE)
	$(SCENE_COMPILE) --info $< > build/$(DEFAULT_SCENE)/scene.info.ron
	$(TRACE) $< --spp 64 --snapshots 1,4,16 --resolution 256x256 --preview build/$(DEFAULT_SCENE)/$(DEFAULT_SCENE)_000064spp.png
	$(AOV_WRITE) $< --spp 64 --snapshots 1,4,16 --resolution 256x256
	$(DENOISE) --model $(DEFAULT_MODEL) --preview $(foreach s,000001 000004 000016 000064,build/$(DEFAULT_SCENE)/$(DEFAULT_SCENE)_$(s)spp.hdr.exr)
	$(ESTIMATE) sensors $< --paths 200000 --csv build/$(DEFAULT_SCENE)/$(DEFAULT_SCENE).sensors.csv
	$(ESTIMATE) image $< --paths 1000 --resolution 256x256 --preview build/$(DEFAULT_SCENE)/$(DEFAULT_SCENE)_001000le.png

scenes: $(COMPILED)

$(RELEASE)/scene-compile: $(RUST_SOURCES)
	$(CARGO) build --release -p scene-compile
	@touch $@

$(RELEASE)/estimate: $(RUST_SOURCES)
	$(CARGO) build --release -p estimate
	@touch $@

$(RELEASE)/trace: $(RUST_SOURCES)
	$(CARGO) build --release -p trace
	@touch $@

$(RELEASE)/aov-write: $(RUST_SOURCES)
	$(CARGO) build --release -p aov-write
	@touch $@

$(RELEASE)/denoise: $(RUST_SOURCES)
	$(CARGO) build --release -p denoise
	@touch $@

$(RELEASE)/evaluate: $(RUST_SOURCES)
	$(CARGO) build --release -p evaluate
	@touch $@

# The local estimate against exact solutions (Sobolev, integrating sphere, CIE 171 5.8) and
# the direct-simulation baseline; fails if any |z| > 4.
validate: $(SCENE_COMPILE) $(ESTIMATE) $(TRACE)
	SCENE_COMPILE=$(SCENE_COMPILE) ESTIMATE=$(ESTIMATE) TRACE=$(TRACE) PRESET=$(PRESET) python3 pipelines/validate.py

# The compiled scene depends on its source, the meshes it may load and the compiler.
build/%/scene.lxs: scenes/%.ron $(MESHES) $(SCENE_COMPILE)
	$(SCENE_COMPILE) $< -o $@

singularity: $(SCENE_COMPILE) $(ESTIMATE)
	SCENE_COMPILE=$(SCENE_COMPILE) ESTIMATE=$(ESTIMATE) PRESET=$(PRESET) python3 pipelines/singularity.py

lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings

test: lint pytest
	$(CARGO) test --workspace

VENV := .venv
PYTHON := $(VENV)/bin/python

$(VENV)/.luxest-setup-2: scripts/setup-python.sh training/requirements.txt
	scripts/setup-python.sh

pytest: $(VENV)/.luxest-setup-2
	$(PYTHON) -m pytest training/tests -q

# The denoiser: preprocess the dataset, train (TRAIN_STEPS / TRAIN_MINUTES), export ONNX, and
# score it on the held-out test scenes. PRESET=quick fits 30 minutes on 2 cores.
TRAIN_STEPS_quick := 6000
TRAIN_MINUTES_quick := 22
TRAIN_STEPS_full := 60000
TRAIN_MINUTES_full := 600
TRAIN_STEPS ?= $(TRAIN_STEPS_$(PRESET))
TRAIN_MINUTES ?= $(TRAIN_MINUTES_$(PRESET))
MODEL := models/$(DATASET).onnx

train: $(MODEL)

$(MODEL): $(VENV)/.luxest-setup-2 $(wildcard training/*.py) | reference noisy
	cd training && ../$(PYTHON) preprocess.py --data-dir ../$(DATA_DIR) --prep-dir ../build/train/$(DATASET)
	cd training && ../$(PYTHON) train.py --prep-dir ../build/train/$(DATASET) --run-dir ../runs/$(DATASET) \
		--steps $(TRAIN_STEPS) --minutes $(TRAIN_MINUTES)
	cd training && ../$(PYTHON) export.py --run-dir ../runs/$(DATASET) --out ../$@
	cd training && ../$(PYTHON) compare_image.py --model ../$@ --split-dir ../$(DATA_DIR)/test \
		--json ../models/$(DATASET).metrics.json
	cp runs/$(DATASET)/config.json models/$(DATASET).config.json

# The evaluation (pipelines/eval.py): error vs time and samples of path tracing, + denoise,
# double local estimate, + denoise on cornell-box and the held-out test scenes, with Pareto
# fronts; the progressive cornell-box experiment (time to SSIM 0.95 / 0.98, noisy vs denoised);
# sensor results vs exact solutions. Writes reports/summary.md, reports/plots, reports/csv.
EVAL_MODEL ?= $(MODEL)

eval: build/cornell-box/scene.lxs $(EVAL_MODEL) $(SCENE_COMPILE) $(TRACE) $(AOV_WRITE) $(ESTIMATE) $(DENOISE) $(EVALUATE) $(VENV)/.luxest-setup-2 | reference noisy
	SCENE_COMPILE=$(SCENE_COMPILE) TRACE=$(TRACE) AOV_WRITE=$(AOV_WRITE) ESTIMATE=$(ESTIMATE) \
		DENOISE=$(DENOISE) EVALUATE=$(EVALUATE) MODEL=$(EVAL_MODEL) DATA_DIR=$(DATA_DIR) PRESET=$(PRESET) \
		$(PYTHON) pipelines/eval.py

bench: build/sobolev/scene.lxs build/cie171-5.8/scene.lxs build/cornell-box/scene.lxs build/bench-1m/scene.lxs
	$(CARGO) bench -p scene-compile --bench compile_1m
	$(CARGO) bench -p estimate --bench estimate
	$(CARGO) bench -p trace --bench trace
	$(CARGO) bench -p denoise --bench denoise

# A 1M-triangle scene for the trace benchmark.
build/bench-1m/scene.lxs: pipelines/bench_scene.py $(SCENE_COMPILE)
	python3 pipelines/bench_scene.py
	$(SCENE_COMPILE) build/bench-1m/scene.ron -o $@

clean:
	rm -rf build data
