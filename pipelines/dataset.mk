# Denoiser datasets: `make reference noisy` renders every generated scene of the preset into
# data/<dataset>/<split>/ in the Intel Open Image Denoise training-toolkit naming:
#   <name>_ref.{hdr,alb,nrm}.exr               reference (REF_SPP samples per pixel)
#   <name>_<spp, 6 digits>spp.{hdr,alb,nrm}.exr  noisy levels 1, 2, 4, ... 64 spp
# Splits (train / valid / test) come from data-gen/generate.py. Incremental: a scene is
# re-rendered only when its .ron (or a stage binary) changes; make prints each step.

DATASET ?= $(PRESET)
GEN_DIR := build/dataset/$(DATASET)/scenes
DATA_DIR := data/$(DATASET)
DATASET_SCENES := $(shell python3 data-gen/generate.py --preset $(PRESET) --list)
REF_SPP_quick := 256
REF_SPP_full := 4096
REF_SPP ?= $(REF_SPP_$(PRESET))
NOISY_LEVELS ?= 1,2,4,8,16,32,64
NOISY_MAX := 64

.PHONY: reference noisy dataset-scenes

# The generator writes every scene of the preset but rewrites only files whose text changed,
# so running it for each out-of-date scene is cheap and keeps untouched scenes' timestamps.
# The scene files are kept (not deleted as intermediates of the render chain).
.SECONDARY: $(patsubst %,$(GEN_DIR)/%.ron,$(DATASET_SCENES)) $(patsubst %,build/dataset/$(DATASET)/%.lxs,$(DATASET_SCENES))

$(GEN_DIR)/%.ron: data-gen/generate.py $(MESHES)
	@python3 data-gen/generate.py --preset $(PRESET) --out $(GEN_DIR)

build/dataset/$(DATASET)/%.lxs: $(GEN_DIR)/%.ron $(SCENE_COMPILE)
	$(SCENE_COMPILE) -q $< -o $@

# The normal image is written last, so it marks a complete set.
$(DATA_DIR)/%_ref.nrm.exr: build/dataset/$(DATASET)/%.lxs $(TRACE) $(AOV_WRITE)
	$(TRACE) $< --spp $(REF_SPP) --reference -o $(DATA_DIR)/$*
	$(AOV_WRITE) $< --spp $(REF_SPP) --reference -o $(DATA_DIR)/$*

$(DATA_DIR)/%_000064spp.nrm.exr: build/dataset/$(DATASET)/%.lxs $(TRACE) $(AOV_WRITE)
	$(TRACE) $< --spp $(NOISY_MAX) --snapshots $(NOISY_LEVELS) -o $(DATA_DIR)/$*
	$(AOV_WRITE) $< --spp $(NOISY_MAX) --snapshots $(NOISY_LEVELS) -o $(DATA_DIR)/$*

dataset-scenes: $(patsubst %,build/dataset/$(DATASET)/%.lxs,$(DATASET_SCENES))
reference: $(patsubst %,$(DATA_DIR)/%_ref.nrm.exr,$(DATASET_SCENES))
noisy: $(patsubst %,$(DATA_DIR)/%_000064spp.nrm.exr,$(DATASET_SCENES))
