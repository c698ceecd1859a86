# Denoiser datasets: `make reference noisy` renders every generated scene of the preset into
# data/<dataset>/<split>/ in the Intel Open Image Denoise training-toolkit naming
# (pipelines/naming.mk):
#   <name>_ref.{hdr,alb,emi,ema,nrm}.exr         reference: REF_SPP samples per pixel, seed REF_SEED
#   <name>_<spp, 6 digits>spp.{hdr,alb,emi,ema,nrm}.exr  noisy levels NOISY_LEVELS, seed NOISY_SEED
#   <name>_<paths, 6 digits>le.hdr.exr           double local estimate at DATASET_DLE light
#                                                paths, seed NOISY_SEED (train and valid scenes;
#                                                training pairs it with the NOISY_MAX features)
# (pipelines/presets.mk). trace and aov-write get the same --seed for each image, so the features
# have the pixel positions of the radiance they go with (albedo and normal at least FEATURE_SPP
# samples: trace's and the next of the same sequence); the reference's seed differs
# from the noisy one, so it shares none of their samples. Splits (train / valid / test) come from
# data-gen/generate.py. Incremental: a scene is re-rendered only when its .ron (or a stage
# binary: rebuilt when a source cargo lists for it changes, Makefile) changes; make prints each step.

DATASET ?= $(PRESET)
GEN_DIR := build/dataset/$(DATASET)/scenes
DATA_DIR := data/$(DATASET)
GENERATE := python3 data-gen/generate.py --preset $(PRESET) $(if $(DATASET_COUNT),--scenes $(DATASET_COUNT))
DATASET_SCENES := $(shell $(GENERATE) --list)
comma := ,
empty :=
space := $(empty) $(empty)
NOISY_MAX := $(lastword $(NOISY_LEVELS))
NOISY_SNAPSHOTS := $(subst $(space),$(comma),$(strip $(NOISY_LEVELS)))

.PHONY: reference noisy dataset-scenes

# The generator writes every scene of the preset but rewrites only files whose text changed,
# so running it for each out-of-date scene is cheap and keeps untouched scenes' timestamps.
# (The scene files are kept: the Makefile's .SECONDARY keeps every file make builds.)
# After generate.py changes, unchanged scenes stay older than it, so make runs the generator on
# every call (a fraction of a second) and `make -n` lists their compile and render steps too; a
# real run re-reads the unchanged scenes' times and skips those steps.

# DATASET_SIDE is part of what a scene is (its camera's resolution): a stamp named after it
# regenerates the scenes when it changes (the generator rewrites the files whose text changed).
SIDE_STAMP := $(call lx_stamp,build/dataset/$(DATASET),side,$(DATASET_SIDE))

$(GEN_DIR)/%.ron: data-gen/generate.py data-gen/textures.py $(MESHES) $(SIDE_STAMP)
	@$(GENERATE) --side $(DATASET_SIDE) --out $(GEN_DIR) --only scenes

# The procedural texture library the scenes name (../textures/<name>.png, data-gen/textures.py),
# one per dataset: a few seconds to write, so written once per change of the generator, by the
# rule of a stamp (the generator rewrites only the images whose bytes changed, and make re-reads
# their times, so an unchanged image leaves its scenes compiled). A missing image removes the
# stamp when make reads this file, so the library is written again.
DATASET_TEXTURES := $(addprefix $(GEN_DIR)/,$(shell python3 data-gen/generate.py --list-textures))
TEXTURE_STAMP := build/dataset/$(DATASET)/textures.stamp
$(if $(filter-out $(wildcard $(DATASET_TEXTURES)),$(DATASET_TEXTURES)),$(shell rm -f $(TEXTURE_STAMP)))
$(TEXTURE_STAMP): data-gen/generate.py data-gen/textures.py
	@$(GENERATE) --out $(GEN_DIR) --only textures && touch $@
$(DATASET_TEXTURES): $(TEXTURE_STAMP) ;

# A compiled scene holds its textures' pixels: it depends on the library too.
build/dataset/$(DATASET)/%.lxs: $(GEN_DIR)/%.ron $(DATASET_TEXTURES) $(SCENE_COMPILE)
	$(LAUNCH) $(SCENE_COMPILE) -q $< -o $@

# REF_SPP is part of what a reference is: a stamp named after it (the only one of its kind) is a
# prerequisite of every reference, so changing REF_SPP re-renders them (preprocess.py also
# refuses a reference with fewer samples than its input).
REF_SPP_STAMP := $(call lx_stamp,build/dataset/$(DATASET),reference-spp,$(REF_SPP))

# FEATURE_SPP is part of what a feature image is: a stamp named after it is a prerequisite of
# every feature set (aov-write --min-samples), so changing it re-renders the features only.
FEATURE_SPP_STAMP := $(call lx_stamp,build/dataset/$(DATASET),feature-spp,$(FEATURE_SPP))

# Radiance (trace) and features (aov-write) in rules of their own, so that a change of one
# stage or of FEATURE_SPP does not re-render the other. The normal image is written last, so
# it marks a complete feature set; the radiance of the last level marks a complete progressive
# run.
$(call lx_ref,$(DATA_DIR)/%,hdr): build/dataset/$(DATASET)/%.lxs $(TRACE) $(REF_SPP_STAMP)
	$(LAUNCH) $(TRACE) $< --spp $(REF_SPP) --reference --seed $(REF_SEED) -o $(DATA_DIR)/$*
$(call lx_ref,$(DATA_DIR)/%,nrm): build/dataset/$(DATASET)/%.lxs $(AOV_WRITE) $(REF_SPP_STAMP) $(FEATURE_SPP_STAMP)
	$(LAUNCH) $(AOV_WRITE) $< --spp $(REF_SPP) --reference --seed $(REF_SEED) --min-samples $(FEATURE_SPP) -o $(DATA_DIR)/$*

$(call lx_image,$(DATA_DIR)/%,$(NOISY_MAX),hdr): build/dataset/$(DATASET)/%.lxs $(TRACE)
	$(LAUNCH) $(TRACE) $< --spp $(NOISY_MAX) --snapshots $(NOISY_SNAPSHOTS) --seed $(NOISY_SEED) -o $(DATA_DIR)/$*
$(call lx_image,$(DATA_DIR)/%,$(NOISY_MAX),nrm): build/dataset/$(DATASET)/%.lxs $(AOV_WRITE) $(FEATURE_SPP_STAMP)
	$(LAUNCH) $(AOV_WRITE) $< --spp $(NOISY_MAX) --snapshots $(NOISY_SNAPSHOTS) --seed $(NOISY_SEED) --min-samples $(FEATURE_SPP) -o $(DATA_DIR)/$*

# Extra noise realizations of the training scenes (NOISY_EXTRA_SEEDS, pipelines/presets.mk): the
# levels NOISY_EXTRA_LEVELS that are noisy levels rendered again with each of these seeds into
# $(DATA_DIR)/train/seed<k>/ under the same names, radiance and features in one rule (the normal
# image, written last, marks the set); preprocess.py pairs them with the scene's reference, and
# training draws a scene's level first, then one of its realizations.
NOISY_EXTRA := $(filter $(NOISY_EXTRA_LEVELS),$(NOISY_LEVELS))
NOISY_EXTRA_MAX := $(lastword $(NOISY_EXTRA))
NOISY_EXTRA_SNAPSHOTS := $(subst $(space),$(comma),$(strip $(NOISY_EXTRA)))
ifneq ($(filter $(NOISY_SEED) $(REF_SEED),$(NOISY_EXTRA_SEEDS)),)
$(error NOISY_EXTRA_SEEDS=$(NOISY_EXTRA_SEEDS): must not contain NOISY_SEED ($(NOISY_SEED)) or REF_SEED ($(REF_SEED)))
endif
DATASET_TRAIN_SCENES := $(patsubst train/%,%,$(filter train/%,$(DATASET_SCENES)))
# $(call extra_prefix,SCENE,SEED): the realization's output prefix; extra_set: its last normal image.
extra_prefix = $(call lx_realization,$(DATA_DIR)/train,$(2))/$(1)
extra_set = $(call lx_image,$(call extra_prefix,$(1),$(2)),$(NOISY_EXTRA_MAX),nrm)
define dataset_realization
$(call extra_set,$(1),$(2)): build/dataset/$(DATASET)/train/$(1).lxs $(TRACE) $(AOV_WRITE) $(FEATURE_SPP_STAMP)
	@mkdir -p $(call lx_realization,$(DATA_DIR)/train,$(2))
	$$(LAUNCH) $$(TRACE) $$< --spp $(NOISY_EXTRA_MAX) --snapshots $(NOISY_EXTRA_SNAPSHOTS) --seed $(2) -o $(call extra_prefix,$(1),$(2))
	$$(LAUNCH) $$(AOV_WRITE) $$< --spp $(NOISY_EXTRA_MAX) --snapshots $(NOISY_EXTRA_SNAPSHOTS) --seed $(2) --min-samples $(FEATURE_SPP) -o $(call extra_prefix,$(1),$(2))
endef
DATASET_REALIZATIONS :=
ifneq ($(NOISY_EXTRA),)
$(foreach s,$(DATASET_TRAIN_SCENES),$(foreach k,$(NOISY_EXTRA_SEEDS),$(eval $(call dataset_realization,$(s),$(k)))))
DATASET_REALIZATIONS := $(foreach s,$(DATASET_TRAIN_SCENES),$(foreach k,$(NOISY_EXTRA_SEEDS),$(call extra_set,$(s),$(k))))
endif

# The features at each level's own sample count (OIDN trains with noisy auxiliary images too):
# the levels below FEATURE_SPP (at and above it both sets are the same images) written by
# aov-write --min-samples 1, seed NOISY_SEED (the samples of the split's radiance of the
# level) into $(DATA_DIR)/<split>/own/ (luxest_contract.OWN_FEATURES_DIR) under the scene's own
# names; preprocess.py pairs them with the split's radiance and reference, and training draws
# one of the two feature sets per crop. Test scenes too (make eval scores both kinds).
NOISY_OWN := $(shell for l in $(NOISY_LEVELS); do [ $$l -lt $(FEATURE_SPP) ] && echo $$l; done)
NOISY_OWN_MAX := $(lastword $(NOISY_OWN))
NOISY_OWN_SNAPSHOTS := $(subst $(space),$(comma),$(strip $(NOISY_OWN)))
own_prefix = $(call lx_own,$(DATA_DIR)/$(patsubst %/,%,$(dir $(1))))/$(notdir $(1))
own_set = $(call lx_image,$(call own_prefix,$(1)),$(NOISY_OWN_MAX),nrm)
define dataset_own
$(call own_set,$(1)): build/dataset/$(DATASET)/$(1).lxs $(AOV_WRITE)
	@mkdir -p $(call lx_own,$(DATA_DIR)/$(patsubst %/,%,$(dir $(1))))
	$$(LAUNCH) $$(AOV_WRITE) $$< --spp $(NOISY_OWN_MAX) --snapshots $(NOISY_OWN_SNAPSHOTS) --seed $(NOISY_SEED) --min-samples 1 -o $(call own_prefix,$(1))
endef
DATASET_OWN :=
ifneq ($(NOISY_OWN),)
$(foreach s,$(DATASET_SCENES),$(eval $(call dataset_own,$(s))))
DATASET_OWN := $(foreach s,$(DATASET_SCENES),$(call own_set,$(s)))
endif

# The local-estimate family (not for the test scenes: make eval renders theirs).
DATASET_LE_SCENES := $(filter-out test/%,$(DATASET_SCENES))
define dataset_le
$(call lx_le,$(DATA_DIR)/$(1),$(2),hdr): build/dataset/$(DATASET)/$(1).lxs $(ESTIMATE)
	$$(LAUNCH) $$(ESTIMATE) image $$< --paths $(2) --seed $(NOISY_SEED) -o $$@
endef
$(foreach s,$(DATASET_LE_SCENES),$(foreach n,$(DATASET_DLE),$(eval $(call dataset_le,$(s),$(n)))))

dataset-scenes: $(patsubst %,build/dataset/$(DATASET)/%.lxs,$(DATASET_SCENES))
reference: $(foreach s,$(DATASET_SCENES),$(foreach k,hdr nrm,$(call lx_ref,$(DATA_DIR)/$(s),$(k))))
noisy: $(foreach s,$(DATASET_SCENES),$(foreach k,hdr nrm,$(call lx_image,$(DATA_DIR)/$(s),$(NOISY_MAX),$(k)))) \
	$(foreach s,$(DATASET_LE_SCENES),$(foreach n,$(DATASET_DLE),$(call lx_le,$(DATA_DIR)/$(s),$(n),hdr))) \
	$(DATASET_REALIZATIONS) $(DATASET_OWN)
