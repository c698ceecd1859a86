# luxest pipeline. Every stage is called through a variable so that a researcher can swap one
# for their own program (e.g. `make scenes SCENE_COMPILE=./my-compiler`), as long as it honours
# the contracts in docs/architecture.md. Make is the build system: one rule per output file,
# Python only for per-file work and summaries; every preset value is in pipelines/presets.mk.
#
#   make run       the main job on the default scene (cornell-box): compile, path-traced
#                  snapshots + AOVs, local estimate at its sensors, double-local-estimate image
#   make textured-example  the textured interior (scenes/textured-room.ron): path-traced and
#                  denoised, and its double-local-estimate image, with PNG previews
#   make scenes    compile every scene in scenes/ into build/<name>/scene.lxs
#   make test      formatting, lints and all tests (cargo and pytest)
#   make reference noisy   render the generated denoiser dataset (PRESET=quick|full)
#   make validate  local estimate vs exact solutions, direct-simulation baseline
#   make singularity  kernel regularisation at Cornell-box corners (bias, variance vs eps)
#   make train     train the denoiser on that dataset, export models/$(DATASET).onnx
#   make eval      the speed/accuracy trade, the progressive experiment and sensor errors:
#                  reports/summary.md (uses models/$(DATASET).onnx; EVAL_MODEL= to choose)
#   make bench     benchmarks (1M-triangle compile + load, local estimate, image, denoise)
#   make lighting  the lighting report of the example office: reports/lighting/office/
#                  (make lighting-radiance recomputes its Radiance peer; scripts/setup.sh --peers)
#   make lighting-daylight  daylight factor and sun against Radiance: reports/lighting/daylight/

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
REPORT ?= $(RELEASE)/report
DEFAULT_MODEL := models/default.onnx

# Launchers, empty by default: every stage call of every rule runs as `$(LAUNCH) $(STAGE) ...`,
# the training step as `$(TRAIN_LAUNCH) python train.py ...`, so that a scheduler runs each one
# as a job step while Make keeps the DAG (README, *On a Slurm cluster*):
#   make -j64 reference noisy LAUNCH="srun --ntasks=1 --cpus-per-task=8 --exact"
#   make train TRAIN_LAUNCH="srun --ntasks=1 --gres=gpu:1"
# A stage's --threads default is the CPUs its process may run on (Slurm binds a step to its
# --cpus-per-task), so a step of -c8 runs eight threads.
LAUNCH ?=
TRAIN_LAUNCH ?= $(LAUNCH)

SCENES := $(basename $(notdir $(wildcard scenes/*.ron)))
COMPILED := $(patsubst %,build/%/scene.lxs,$(SCENES))
RUST_SOURCES := $(shell find crates -name '*.rs' -o -name Cargo.toml) Cargo.toml Cargo.lock
MESHES := $(wildcard scenes/meshes/*)
# The images the example scenes name (data-gen/example_textures.py writes them).
SCENE_TEXTURES := $(wildcard scenes/textures/*)

VENV := .venv
VENV_STAMP := .luxest-setup-4
PYTHON := $(VENV)/bin/python

.PHONY: run textured-example scenes test lint bench validate singularity clean train pytest eval test-slurm rust-test
# Every file make builds is kept: none is a throwaway intermediate (compiled scenes, renders).
.SECONDARY:

# $(call lx_stamp,DIR,NAME,VALUE): the file DIR/NAME-VALUE, the only NAME-* in DIR, made when make
# reads the makefiles (in a dry run too) if it is missing, the others removed; its path. A
# prerequisite of the outputs that depend on VALUE, so that a changed VALUE makes them out of date.
# Not made by a rule: under `.SECONDARY:` GNU make 4.3 treats a missing file that has a rule and no
# prerequisites as present, so a changed value would go unnoticed (training/tests/test_make.py
# runs make to check).
lx_stamp = $(shell mkdir -p $(1) && { [ -e $(1)/$(2)-$(3) ] || { rm -f $(1)/$(2)-*; touch $(1)/$(2)-$(3); }; } && echo $(1)/$(2)-$(3))

include pipelines/presets.mk
include pipelines/naming.mk
include pipelines/dataset.mk
# The model `make train` writes and `make eval` scores by default (EVAL_MODEL). Defined before
# eval.mk, whose per-scene rules expand it when they are defined.
MODEL := models/$(DATASET).onnx
include pipelines/validate.mk
include pipelines/singularity.mk
include pipelines/eval.mk
include pipelines/lighting.mk
include pipelines/daylight.mk
# The Mitsuba 3 cross-check (make mitsuba-check).
include pipelines/mitsuba.mk
include pipelines/bench.mk

# The main job on the default scene: compile it, path-trace snapshots with their albedo and
# normal features and denoise them (the committed model), estimate illuminance at its sensors
# (local estimate), render its double-local-estimate luminance image with a PNG preview.
RUN_PREFIX := build/$(DEFAULT_SCENE)/$(DEFAULT_SCENE)
run: build/$(DEFAULT_SCENE)/scene.lxs $(ESTIMATE) $(TRACE) $(AOV_WRITE) $(DENOISE)
	$(LAUNCH) $(SCENE_COMPILE) --info $< > build/$(DEFAULT_SCENE)/scene.info.ron
	$(LAUNCH) $(TRACE) $< --spp 64 --snapshots 1,4,16 --resolution 256x256 --preview $(RUN_PREFIX)_$(call lx_count,64)spp.png
	$(LAUNCH) $(AOV_WRITE) $< --spp 64 --snapshots 1,4,16 --min-samples $(FEATURE_SPP) --resolution 256x256
	$(LAUNCH) $(DENOISE) --model $(DEFAULT_MODEL) --preview $(foreach s,1 4 16 64,$(call lx_image,$(RUN_PREFIX),$(s),hdr))
	$(LAUNCH) $(ESTIMATE) sensors $< --paths 200000 --csv $(RUN_PREFIX).sensors.csv
	$(LAUNCH) $(ESTIMATE) image $< --paths 300 --resolution 256x256 --preview $(RUN_PREFIX)_$(call lx_count,300)le.png

# The textured interior: path-traced at 64 spp with its features and denoised by the committed
# model, and its double-local-estimate image (300 light paths per sensor), PNG previews beside.
TEXTURED_PREFIX := build/textured-room/textured-room
textured-example: build/textured-room/scene.lxs $(TRACE) $(AOV_WRITE) $(ESTIMATE) $(DENOISE)
	$(LAUNCH) $(TRACE) $< --spp 64 --snapshots 16 --preview $(TEXTURED_PREFIX)_$(call lx_count,64)spp.png
	$(LAUNCH) $(AOV_WRITE) $< --spp 64 --snapshots 16 --min-samples $(FEATURE_SPP)
	$(LAUNCH) $(DENOISE) --model $(DEFAULT_MODEL) --preview $(foreach s,16 64,$(call lx_image,$(TEXTURED_PREFIX),$(s),hdr))
	$(LAUNCH) $(ESTIMATE) image $< --paths 300 --preview $(TEXTURED_PREFIX)_$(call lx_count,300)le.png

scenes: $(COMPILED)

# The stage binaries: one rule for all of them. Each depends on the sources cargo's dep-info lists
# for it (target/release/<stage>.d, written beside the binary; its target, an absolute path, cut
# off), so an edit of one stage's crate rebuilds that stage alone and leaves the images the others
# made current; before the first build, or when a listed file is gone, on every source.
STAGE_BINS := scene-compile trace aov-write estimate denoise evaluate report
CARGO_MANIFESTS := $(shell find crates -name Cargo.toml) Cargo.toml Cargo.lock
stage_listed = $(if $(wildcard $(RELEASE)/$(1).d),$(shell sed -e '1s/^[^:]*: *//' -e '1q' $(RELEASE)/$(1).d))
stage_sources = $(if $(1),$(if $(filter-out $(wildcard $(1)),$(1)),$(RUST_SOURCES),$(1)),$(RUST_SOURCES))
$(foreach b,$(STAGE_BINS),$(eval $(RELEASE)/$(b): $(call stage_sources,$(call stage_listed,$(b))) $(CARGO_MANIFESTS)))
$(addprefix $(RELEASE)/,$(STAGE_BINS)): $(RELEASE)/%:
	$(CARGO) build --release -p $*
	@touch $@

# The compiled scene depends on its source, the meshes and images it may load and the compiler.
build/%/scene.lxs: scenes/%.ron $(MESHES) $(SCENE_TEXTURES) $(SCENE_COMPILE)
	$(LAUNCH) $(SCENE_COMPILE) $< -o $@

# The Python sources' formatting (ruff.toml); make test checks it too (training/tests/test_tidy.py).
PYTHON_SOURCES := training pipelines data-gen python

lint: $(VENV)/$(VENV_STAMP)
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings
	$(VENV)/bin/ruff format --check $(PYTHON_SOURCES)

# make test lints as make lint does, in the one build that links the tests: clippy-driver is the
# compiler of the workspace's own crates (RUSTC_WORKSPACE_WRAPPER, as cargo clippy sets it, with
# its -D warnings in CLIPPY_ARGS), so the dependencies are not built a second time for a check.
CLIPPY_BUILD := RUSTC_WORKSPACE_WRAPPER=clippy-driver CLIPPY_ARGS=-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__

# make test runs pytest and the Rust checks side by side (make -j2; each one's output shown when it
# ends): pytest's processes wait on its two export workers part of the time, and the one build
# that lints and links the tests fills the cores. Budget: docs/architecture.md, *Test time budget*.
test: $(VENV)/$(VENV_STAMP)
	$(MAKE) --no-print-directory --output-sync=target -j2 pytest rust-test

# The evaluator and the denoiser are also built as programs and must not link Embree (a
# researcher who swaps the tracer builds them without it; tests/architecture.rs checks the
# dependency graph, this the binaries).
rust-test:
	$(CARGO) fmt --all -- --check
	$(CLIPPY_BUILD) $(CARGO) test --workspace --all-targets --no-run
	$(CLIPPY_BUILD) $(CARGO) test --workspace
	$(CLIPPY_BUILD) $(CARGO) build -p denoise -p evaluate --bins
	@for b in denoise evaluate; do \
		readelf -d target/debug/$$b > target/debug/$$b.dynamic || exit 1; \
		if grep -qi embree target/debug/$$b.dynamic; then echo "error: target/debug/$$b links Embree" >&2; exit 1; fi; \
	done; echo "denoise and evaluate link no Embree"

# The Make DAG through a real single-node Slurm cluster (pipelines/tests/test_slurm.py; set up by
# scripts/slurm-cluster.sh, Slurm and munge from scripts/setup.sh), with the debug stage programs
# make test builds: about a minute, so a target of its own, which CI runs after make test. With
# the same programs, every generated room compiled with its textures
# (pipelines/tests/test_generated_scenes.py, seconds).
test-slurm: $(VENV)/$(VENV_STAMP)
	$(CLIPPY_BUILD) $(CARGO) build $(addprefix -p ,$(STAGE_BINS)) --bins
	MAKEFLAGS= MAKELEVEL= LUXEST_BIN_DIR=target/debug $(PYTHON) -m pytest pipelines/tests -q

$(VENV)/$(VENV_STAMP): scripts/setup-python.sh training/requirements.txt
	scripts/setup-python.sh

# The tests run make themselves: without this make's jobserver (MAKEFLAGS), whose -j2 of make test
# their makes would otherwise join, with a warning on stderr.
pytest: $(VENV)/$(VENV_STAMP)
	MAKEFLAGS= MAKELEVEL= $(PYTHON) -m pytest training/tests -q

# The denoiser: preprocess the dataset, train (TRAIN_STEPS / TRAIN_MINUTES / TRAIN_SCHEDULE / TRAIN_LOSS), export ONNX, and
# score it on the held-out test scenes with the evaluate stage (MODEL: defined before eval.mk).
# A finished run (runs/<dataset>/summary.json written) is trained anew; an unfinished one (killed,
# pre-empted, a requeued Slurm job's earlier try) goes on from its last checkpoint (--resume).

train: $(MODEL)

# A model named on the command line (`make eval EVAL_MODEL=models/quick.onnx`) is an input: make
# does not retrain it, even when it is the one `make train` writes and training/*.py is newer,
# unless `train` is a goal too. Plain `make eval` trains the model it scores when it is missing
# or out of date.
ifeq ($(if $(filter command line,$(origin EVAL_MODEL)),$(if $(filter train,$(MAKECMDGOALS)),,$(filter $(MODEL),$(EVAL_MODEL)))),)
$(MODEL): $(VENV)/$(VENV_STAMP) $(wildcard training/*.py) python/luxest_contract.py $(EVALUATE) | reference noisy
	cd training && $(LAUNCH) ../$(PYTHON) preprocess.py --data-dir ../$(DATA_DIR) --prep-dir ../build/train/$(DATASET) \
		--noisy-spp $(NOISY_LEVELS) --dle-paths $(DATASET_DLE) \
		--extra-seeds $(if $(NOISY_EXTRA),$(NOISY_EXTRA_SEEDS)) --extra-spp $(NOISY_EXTRA)
	@if [ -e runs/$(DATASET)/summary.json ]; then echo "rm -r runs/$(DATASET) (a finished run)"; rm -r runs/$(DATASET); fi
	cd training && $(TRAIN_LAUNCH) ../$(PYTHON) train.py --prep-dir ../build/train/$(DATASET) --run-dir ../runs/$(DATASET) \
		--noisy-spp $(NOISY_LEVELS) --dle-paths $(DATASET_DLE) --extra-seeds $(if $(NOISY_EXTRA),$(NOISY_EXTRA_SEEDS)) \
		--extra-spp $(NOISY_EXTRA) --steps $(TRAIN_STEPS) --minutes $(TRAIN_MINUTES) \
		--schedule $(TRAIN_SCHEDULE) --loss $(TRAIN_LOSS) --resume
	cd training && $(LAUNCH) ../$(PYTHON) export.py --run-dir ../runs/$(DATASET) --out ../$@
	cd training && $(LAUNCH) ../$(PYTHON) compare_image.py --model ../$@ --split-dir ../$(DATA_DIR)/test \
		--work-dir ../build/train/$(DATASET)/compare --evaluate $(if $(findstring /,$(EVALUATE)),$(abspath $(EVALUATE)),$(EVALUATE)) \
		--json ../models/$(DATASET).metrics.json
	cp runs/$(DATASET)/run.json models/$(DATASET).config.json
endif

bench: build/sobolev/scene.lxs build/cie171-5.8/scene.lxs build/cornell-box/scene.lxs build/bench-1m/scene.lxs bench-pt bench-sensors bench-edges bench-denoise
	$(CARGO) bench -p scene-compile --bench compile_1m
	$(CARGO) bench -p estimate --bench estimate
	$(CARGO) bench -p trace --bench trace
	$(CARGO) bench -p denoise --bench denoise

# A 1M-triangle scene for the trace benchmark.
build/bench-1m/scene.ron: pipelines/bench_scene.py
	python3 pipelines/bench_scene.py
build/bench-1m/scene.lxs: build/bench-1m/scene.ron $(SCENE_COMPILE)
	$(LAUNCH) $(SCENE_COMPILE) $< -o $@

clean:
	rm -rf build data
