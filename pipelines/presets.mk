# The presets: every number that `PRESET=quick|full` scales, defined once, here. The Python steps
# receive these values as arguments from the rules; none has its own copy. (The dataset's scene
# count and image size are data-gen/generate.py's, selected by --preset $(PRESET).)
#
# quick fits a 2-core machine: `make reference noisy train eval` in about 45 minutes.

PRESET ?= quick
ifeq ($(filter $(PRESET),quick full),)
$(error PRESET=$(PRESET): expected quick or full)
endif

# Dataset (pipelines/dataset.mk): reference samples per pixel; noisy snapshot levels.
REF_SPP_quick := 256
REF_SPP_full := 4096
NOISY_LEVELS_quick := 1 2 4 8 16 32 64
NOISY_LEVELS_full := 1 2 4 8 16 32 64

# Training (make train): steps of the one-cycle schedule, and the time budget in minutes.
TRAIN_STEPS_quick := 6000
TRAIN_MINUTES_quick := 22
TRAIN_STEPS_full := 60000
TRAIN_MINUTES_full := 600

# Evaluation (pipelines/eval.mk): the Cornell-box reference spp and progressive run's last spp,
# double-local-estimate light paths on the Cornell box, light-tracing paths on the Cornell box
# (the baseline), double-local-estimate paths on the dataset's test scenes, and the
# sensor cases' path counts as a fraction of make validate's.
EVAL_REF_SPP_quick := 4096
EVAL_REF_SPP_full := 65536
EVAL_PROG_SPP_quick := 1024
EVAL_PROG_SPP_full := 8192
EVAL_DLE_quick := 100 300 1000 3000
EVAL_DLE_full := 100 300 1000 3000 10000 30000
EVAL_LT_quick := 1000000 4000000 16000000
EVAL_LT_full := 1000000 4000000 16000000 64000000 256000000
EVAL_DATA_DLE_quick := 100 1000
EVAL_DATA_DLE_full := 100 1000 10000
EVAL_SENSOR_SCALE_quick := 0.25
EVAL_SENSOR_SCALE_full := 1

# Validation (pipelines/validate.mk): multiplier of every case's light paths.
VALIDATE_SCALE_quick := 1
VALIDATE_SCALE_full := 10

# Singularity study (pipelines/singularity.mk): light paths per run, gather samples per sensor.
SINGULARITY_PATHS_quick := 1000000
SINGULARITY_PATHS_full := 10000000
SINGULARITY_SAMPLES_quick := 200000
SINGULARITY_SAMPLES_full := 2000000

# The selected preset's values: each NAME above gets NAME ?= NAME_$(PRESET), so every one is
# also overridable on the command line (`make eval EVAL_DLE="100 1000"`).
PRESET_VARIABLES := REF_SPP NOISY_LEVELS TRAIN_STEPS TRAIN_MINUTES EVAL_REF_SPP EVAL_PROG_SPP \
	EVAL_DLE EVAL_LT EVAL_DATA_DLE EVAL_SENSOR_SCALE VALIDATE_SCALE SINGULARITY_PATHS SINGULARITY_SAMPLES
$(foreach v,$(PRESET_VARIABLES),$(eval $(v) ?= $$($(v)_$(PRESET))))

# Seeds (docs/architecture.md, *Seeds*). A sample depends only on (seed, pixel, sample index), so
# a reference rendered with its noisy images' seed would contain their samples: references use
# their own seed, and preprocess.py refuses a pair whose luxest.seed values are equal.
NOISY_SEED := 1
REF_SEED := 1000001
