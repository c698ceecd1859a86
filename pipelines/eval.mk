# `make eval`: the speed/accuracy trade of every image estimator, the progressive Cornell-box
# experiment and sensor results against exact values -> reports/summary.md (+ reports/plots,
# reports/csv). One rule per output file, every stage through its variable; pipelines/eval.py
# only draws the summary from the reports. Incremental: change the model and only denoised
# images, their reports and the summary are redone.
#
# The reports record wall-clock seconds per image, so a timing run is `make eval` without -j
# (parallel jobs share the cores and inflate each other's seconds); -j is for a quick check.
#
# Sections: (1) Cornell box 256²: a reference of EVAL_REF_SPP spp (seed REF_SEED), one
# progressive run (seed NOISY_SEED) with snapshots at 1, 2, 4, ... and every 64 spp up to
# EVAL_PROG_SPP, its features at the same snapshots, every snapshot denoised; double-local-
# estimate images at EVAL_DLE light paths, each denoised with the 64-spp features; light-tracing
# images at EVAL_LT paths (the baseline). (2) The
# held-out test scenes of the dataset (references: EVAL_HELDOUT_REF_SPP): noisy levels of `make noisy` denoised; local-estimate
# images at EVAL_DATA_DLE paths, denoised with the NOISY_MAX features. (3) The cases of `make validate` at EVAL_SENSOR_SCALE times
# their paths, against exact values. (4) The public interiors of scenes/public/ (EVAL_PUBLIC;
# CC-BY, credited in scenes/public/README.md; never in training): their own references (seed
# REF_SEED), noisy levels EVAL_PUBLIC_SPP, features both antialiased and of each snapshot's own samples,
# double-local-estimate images. Every image luxest's model denoises in (1), (2) and (4) is also
# denoised by Intel Open Image Denoise 1.4.3 and 2.5.1 (the peers; hdr + albedo + normal),
# scored beside it; (1) and (4) also with the features of each snapshot's own samples (the snapshot's own
# samples, not antialiased), in a report of their own.
# A local-estimate image is denoised with the features of a path-traced level (denoise
# --features-of): denoise reads from there the features its model's metadata lists.

EVAL_DIR := build/eval/$(PRESET)
EVAL_MODEL ?= $(MODEL)
EVAL_RES := 256x256
EVAL_CB := $(EVAL_DIR)/cornell-box/cb
EVAL_CB_SCENE := build/cornell-box/scene.lxs
REPORTS ?= reports
EVAL_CSV := $(REPORTS)/csv
EVAL_DLE_FEATURES_SPP := 64
# Which model denoised an image is part of what the image is: a stamp named after EVAL_MODEL
# (lx_stamp) is a prerequisite of every image luxest's model denoises, so switching EVAL_MODEL to
# another file re-denoises them even when that file is older than the images (they once stayed,
# and a summary named a model that had not made them). Made only when a goal is make eval's, so
# that other targets (make run, make test) do not switch it.
EVAL_MODEL_STAMP := $(if $(filter eval $(EVAL_DIR)/% $(REPORTS)/%,$(MAKECMDGOALS)),$(call lx_stamp,$(EVAL_DIR),model,$(subst /,+,$(EVAL_MODEL))))

# (1) Snapshots: powers of two and multiples of 64 up to EVAL_PROG_SPP, ascending.
EVAL_SNAPSHOTS := $(shell (seq 64 64 $(EVAL_PROG_SPP); p=1; while [ $$p -le $(EVAL_PROG_SPP) ]; do echo $$p; p=$$((p * 2)); done) | sort -n -u)
EVAL_LAST := $(lastword $(EVAL_SNAPSHOTS))
eval_cb = $(foreach s,$(EVAL_SNAPSHOTS),$(call lx_image,$(EVAL_CB),$(s),$(1)))
eval_cb_le = $(foreach n,$(EVAL_DLE),$(call lx_le,$(EVAL_CB),$(n),$(1)))
# Light tracing (the baseline of the double local estimate) in its own directory: same names.
EVAL_CB_LT := $(EVAL_DIR)/cornell-box/light-tracing/cb
eval_cb_lt = $(foreach n,$(EVAL_LT),$(call lx_le,$(EVAL_CB_LT),$(n),hdr))

$(call lx_ref,$(EVAL_CB),hdr): $(EVAL_CB_SCENE) $(TRACE)
	@mkdir -p $(@D)
	$(LAUNCH) $(TRACE) $< --spp $(EVAL_REF_SPP) --reference --seed $(REF_SEED) --resolution $(EVAL_RES) -o $(EVAL_CB)

# One progressive run writes every snapshot; the last marks it complete.
$(call lx_image,$(EVAL_CB),$(EVAL_LAST),hdr): $(EVAL_CB_SCENE) $(TRACE)
	@mkdir -p $(@D)
	$(LAUNCH) $(TRACE) $< --spp $(EVAL_LAST) --snapshots $(subst $(space),$(comma),$(EVAL_SNAPSHOTS)) --seed $(NOISY_SEED) --resolution $(EVAL_RES) -o $(EVAL_CB)
$(filter-out $(call lx_image,$(EVAL_CB),$(EVAL_LAST),hdr),$(call eval_cb,hdr)): $(call lx_image,$(EVAL_CB),$(EVAL_LAST),hdr) ;

# Features of at least FEATURE_SPP samples (pipelines/presets.mk), stamped like the dataset's.
$(call lx_image,$(EVAL_CB),$(EVAL_LAST),nrm): $(EVAL_CB_SCENE) $(AOV_WRITE) $(call lx_stamp,$(EVAL_DIR),feature-spp,$(FEATURE_SPP))
	@mkdir -p $(@D)
	$(LAUNCH) $(AOV_WRITE) $< --spp $(EVAL_LAST) --snapshots $(subst $(space),$(comma),$(EVAL_SNAPSHOTS)) --seed $(NOISY_SEED) --min-samples $(FEATURE_SPP) --resolution $(EVAL_RES) -o $(EVAL_CB)
$(filter-out $(call lx_image,$(EVAL_CB),$(EVAL_LAST),nrm),$(foreach k,$(LX_FEATURES),$(call eval_cb,$(k)))): $(call lx_image,$(EVAL_CB),$(EVAL_LAST),nrm) ;

$(call lx_image_pattern,$(EVAL_CB),dn): $(foreach k,hdr $(LX_FEATURES),$(call lx_image_pattern,$(EVAL_CB),$(k))) $(EVAL_MODEL) $(EVAL_MODEL_STAMP) $(DENOISE)
	$(LAUNCH) $(DENOISE) $< --model $(EVAL_MODEL) -o $@

$(call lx_le_pattern,$(EVAL_CB),hdr): $(EVAL_CB_SCENE) $(ESTIMATE)
	@mkdir -p $(@D)
	$(LAUNCH) $(ESTIMATE) image $< --paths $* --seed $(NOISY_SEED) --resolution $(EVAL_RES) -o $@

$(call lx_le_pattern,$(EVAL_CB_LT),hdr): $(EVAL_CB_SCENE) $(ESTIMATE)
	@mkdir -p $(@D)
	$(LAUNCH) $(ESTIMATE) image $< --light-tracing --paths $* --seed $(NOISY_SEED) --resolution $(EVAL_RES) -o $@

$(call lx_le_pattern,$(EVAL_CB),dn): $(call lx_le_pattern,$(EVAL_CB),hdr) $(call lx_features,$(EVAL_CB),$(EVAL_DLE_FEATURES_SPP)) $(EVAL_MODEL) $(EVAL_MODEL_STAMP) $(DENOISE)
	$(LAUNCH) $(DENOISE) $< --model $(EVAL_MODEL) --features-of $(call lx_image,$(EVAL_CB),$(EVAL_DLE_FEATURES_SPP),hdr) -o $@

# Intel Open Image Denoise, the peer, on the same inputs (pipelines/oidn_denoise.py): in an oidn/
# directory beside them, the scene's name suffixed `-oidn` (the FLIP maps share one directory).
OIDN_DENOISE ?= $(PYTHON) pipelines/oidn_denoise.py
EVAL_CB_OIDN := $(EVAL_DIR)/cornell-box/oidn/cb-oidn
eval_cb_oidn = $(foreach s,$(EVAL_SNAPSHOTS),$(call lx_image,$(EVAL_CB_OIDN),$(s),dn)) \
	$(foreach n,$(EVAL_DLE),$(call lx_le,$(EVAL_CB_OIDN),$(n),dn))

$(call lx_image_pattern,$(EVAL_CB_OIDN),dn): $(call lx_image_pattern,$(EVAL_CB),hdr) $(call lx_image_pattern,$(EVAL_CB),alb) $(call lx_image_pattern,$(EVAL_CB),nrm) pipelines/oidn_denoise.py
	@mkdir -p $(@D)
	$(LAUNCH) $(OIDN_DENOISE) $< --alb $(word 2,$^) --nrm $(word 3,$^) -o $@

$(call lx_le_pattern,$(EVAL_CB_OIDN),dn): $(call lx_le_pattern,$(EVAL_CB),hdr) $(call lx_image,$(EVAL_CB),$(EVAL_DLE_FEATURES_SPP),alb) $(call lx_image,$(EVAL_CB),$(EVAL_DLE_FEATURES_SPP),nrm) pipelines/oidn_denoise.py
	@mkdir -p $(@D)
	$(LAUNCH) $(OIDN_DENOISE) $< --alb $(word 2,$^) --nrm $(word 3,$^) -o $@

# Intel Open Image Denoise 2.5.1 (PyPI pyoidn in .venv-peers: scripts/setup.sh --peers), the peer
# at its best quality: `quality high`, and the features as OIDN's documentation recommends for
# each kind — antialiased ones passed as clean (cleanAux), the snapshot's own denoised first by
# their own filters (prefilter; pipelines/oidn_denoise.py). Its command begins with options, its
# images go to oidn2/ directories, suffixed `-oidn2` (evaluate labels them `+oidn2`).
# EVAL_OIDN2 (yes or no): whether its images are scored; yes where .venv-peers has it, otherwise
# no with a warning (a machine set up without --peers still runs make eval, with 1.4.3 alone).
OIDN2_FOUND := $(firstword $(wildcard .venv-peers/lib/python3*/site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2))
OIDN2_LIB ?= $(or $(OIDN2_FOUND),.venv-peers/lib/python3/site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2)
EVAL_OIDN2 ?= $(if $(OIDN2_FOUND),yes,no)
ifeq ($(filter yes no,$(EVAL_OIDN2)),)
$(error EVAL_OIDN2=$(EVAL_OIDN2): expected yes or no)
endif
ifeq ($(EVAL_OIDN2)$(filter eval $(EVAL_DIR)/% $(REPORTS)/% bench-denoise,$(MAKECMDGOALS)),no)
else ifeq ($(EVAL_OIDN2),no)
$(warning OIDN 2.5.1 not found in .venv-peers (scripts/setup.sh --peers installs it): make eval scores OIDN 1.4.3 alone)
endif
if_oidn2 = $(if $(filter yes,$(EVAL_OIDN2)),$(1))
OIDN2_DENOISE ?= $(OIDN_DENOISE) --oidn-lib $(OIDN2_LIB) --quality high
OIDN2_AUX_ANTIALIASED := clean
OIDN2_AUX_DEFAULT := prefilter
EVAL_CB_OIDN2 := $(EVAL_DIR)/cornell-box/oidn2/cb-oidn2
eval_cb_oidn2 = $(foreach s,$(EVAL_SNAPSHOTS),$(call lx_image,$(EVAL_CB_OIDN2),$(s),dn)) \
	$(foreach n,$(EVAL_DLE),$(call lx_le,$(EVAL_CB_OIDN2),$(n),dn))

$(call lx_image_pattern,$(EVAL_CB_OIDN2),dn): $(call lx_image_pattern,$(EVAL_CB),hdr) $(call lx_image_pattern,$(EVAL_CB),alb) $(call lx_image_pattern,$(EVAL_CB),nrm) pipelines/oidn_denoise.py
	@mkdir -p $(@D)
	$(LAUNCH) $(OIDN2_DENOISE) --aux $(OIDN2_AUX_ANTIALIASED) $< --alb $(word 2,$^) --nrm $(word 3,$^) -o $@

$(call lx_le_pattern,$(EVAL_CB_OIDN2),dn): $(call lx_le_pattern,$(EVAL_CB),hdr) $(call lx_image,$(EVAL_CB),$(EVAL_DLE_FEATURES_SPP),alb) $(call lx_image,$(EVAL_CB),$(EVAL_DLE_FEATURES_SPP),nrm) pipelines/oidn_denoise.py
	@mkdir -p $(@D)
	$(LAUNCH) $(OIDN2_DENOISE) --aux $(OIDN2_AUX_ANTIALIASED) $< --alb $(word 2,$^) --nrm $(word 3,$^) -o $@

$(EVAL_CSV)/cornell-box.images.csv: $(call lx_ref,$(EVAL_CB),hdr) $(call eval_cb,hdr) $(call eval_cb,dn) $(call eval_cb_le,hdr) $(call eval_cb_le,dn) $(eval_cb_lt) $(eval_cb_oidn) $(call if_oidn2,$(eval_cb_oidn2)) $(EVALUATE)
	@mkdir -p $(@D) $(EVAL_DIR)/flip
	$(LAUNCH) $(EVALUATE) images --reference $< $(filter-out $< $(EVALUATE),$^) -o $@ --ron $(@:.csv=.ron) --flip-maps $(EVAL_DIR)/flip

# The same progressive run denoised with the features of each snapshot's own samples (aov-write --min-samples 1: each
# snapshot's features average that snapshot's own samples, same seed), at the powers of two up to
# EVAL_PROG_SPP: luxest's model (denoise --features-of --any-feature-samples: the committed
# model asks for antialiased ones and refuses these otherwise), OIDN 1.4.3 (features as they are) and
# OIDN 2.5.1 (prefiltered), in directories of their own; a report of their own (the labels are
# those of the antialiased report).
EVAL_DF_SNAPSHOTS := $(shell p=1; while [ $$p -le $(EVAL_PROG_SPP) ]; do echo $$p; p=$$((p * 2)); done)
EVAL_DF_LAST := $(lastword $(EVAL_DF_SNAPSHOTS))
EVAL_CB_DF := $(EVAL_DIR)/cornell-box/own-features/cb
EVAL_CB_DF_DN := $(EVAL_DIR)/cornell-box/own-features/cb-df
EVAL_CB_DF_OIDN := $(EVAL_DIR)/cornell-box/own-features/oidn/cb-df-oidn
EVAL_CB_DF_OIDN2 := $(EVAL_DIR)/cornell-box/own-features/oidn2/cb-df-oidn2

$(call lx_image,$(EVAL_CB_DF),$(EVAL_DF_LAST),nrm): $(EVAL_CB_SCENE) $(AOV_WRITE)
	@mkdir -p $(@D)
	$(LAUNCH) $(AOV_WRITE) $< --spp $(EVAL_DF_LAST) --snapshots $(subst $(space),$(comma),$(EVAL_DF_SNAPSHOTS)) --seed $(NOISY_SEED) --min-samples 1 --resolution $(EVAL_RES) -o $(EVAL_CB_DF)
$(filter-out $(call lx_image,$(EVAL_CB_DF),$(EVAL_DF_LAST),nrm),$(foreach k,$(LX_FEATURES),$(foreach s,$(EVAL_DF_SNAPSHOTS),$(call lx_image,$(EVAL_CB_DF),$(s),$(k))))): $(call lx_image,$(EVAL_CB_DF),$(EVAL_DF_LAST),nrm) ;

$(call lx_image_pattern,$(EVAL_CB_DF_DN),dn): $(call lx_image_pattern,$(EVAL_CB),hdr) $(foreach k,$(LX_FEATURES),$(call lx_image_pattern,$(EVAL_CB_DF),$(k))) $(EVAL_MODEL) $(EVAL_MODEL_STAMP) $(DENOISE)
	$(LAUNCH) $(DENOISE) $< --model $(EVAL_MODEL) --any-feature-samples --features-of $(EVAL_CB_DF)_$*spp.hdr.exr -o $@

$(call lx_image_pattern,$(EVAL_CB_DF_OIDN),dn): $(call lx_image_pattern,$(EVAL_CB),hdr) $(call lx_image_pattern,$(EVAL_CB_DF),alb) $(call lx_image_pattern,$(EVAL_CB_DF),nrm) pipelines/oidn_denoise.py
	@mkdir -p $(@D)
	$(LAUNCH) $(OIDN_DENOISE) $< --alb $(word 2,$^) --nrm $(word 3,$^) -o $@

$(call lx_image_pattern,$(EVAL_CB_DF_OIDN2),dn): $(call lx_image_pattern,$(EVAL_CB),hdr) $(call lx_image_pattern,$(EVAL_CB_DF),alb) $(call lx_image_pattern,$(EVAL_CB_DF),nrm) pipelines/oidn_denoise.py
	@mkdir -p $(@D)
	$(LAUNCH) $(OIDN2_DENOISE) --aux $(OIDN2_AUX_DEFAULT) $< --alb $(word 2,$^) --nrm $(word 3,$^) -o $@

$(EVAL_CSV)/cornell-box-own-features.images.csv: $(call lx_ref,$(EVAL_CB),hdr) \
		$(foreach s,$(EVAL_DF_SNAPSHOTS),$(call lx_image,$(EVAL_CB),$(s),hdr) $(call lx_image,$(EVAL_CB_DF_DN),$(s),dn) $(call lx_image,$(EVAL_CB_DF_OIDN),$(s),dn) $(call if_oidn2,$(call lx_image,$(EVAL_CB_DF_OIDN2),$(s),dn))) $(EVALUATE)
	@mkdir -p $(@D) $(EVAL_DIR)/flip/cornell-box-own-features
	$(LAUNCH) $(EVALUATE) images --reference $< $(filter-out $< $(EVALUATE),$^) -o $@ --ron $(@:.csv=.ron) --flip-maps $(EVAL_DIR)/flip/cornell-box-own-features

# (2) The held-out test scenes (references and noisy levels from make reference noisy; the
#    local-estimate images from the scenes compiled for the dataset).
EVAL_DATA := $(DATA_DIR)/test
EVAL_DS := $(EVAL_DIR)/dataset
EVAL_TEST_SCENES := $(patsubst test/%,%,$(filter test/%,$(DATASET_SCENES)))
# Their references: the dataset's own (REF_SPP samples, seed REF_SEED) unless
# EVAL_HELDOUT_REF_SPP asks for another count; then make eval renders its own from the dataset's
# compiled scene, with the same seed (independent of every noisy level and local-estimate image),
# into a directory named after the count. The quick dataset's references have as many samples as
# its top noisy level, so their own noise is half of that level's error against them
# (docs/measurements.md). A stamp named after the count makes the reports follow a change of it.
EVAL_HELDOUT_REF_SPP ?= $(REF_SPP)
eval_heldout_ref = $(if $(filter $(REF_SPP),$(EVAL_HELDOUT_REF_SPP)),$(call lx_ref,$(EVAL_DATA)/$(1),hdr),$(call lx_ref,$(EVAL_DS)/ref-$(EVAL_HELDOUT_REF_SPP)/$(1),hdr))
EVAL_HELDOUT_REF_STAMP := $(if $(filter eval $(EVAL_DIR)/% $(REPORTS)/%,$(MAKECMDGOALS)),$(call lx_stamp,$(EVAL_DIR),heldout-ref-spp,$(EVAL_HELDOUT_REF_SPP)))

$(call lx_ref,$(EVAL_DS)/ref-$(EVAL_HELDOUT_REF_SPP)/%,hdr): build/dataset/$(DATASET)/test/%.lxs $(TRACE)
	@mkdir -p $(@D)
	$(LAUNCH) $(TRACE) $< --spp $(EVAL_HELDOUT_REF_SPP) --reference --seed $(REF_SEED) -o $(EVAL_DS)/ref-$(EVAL_HELDOUT_REF_SPP)/$*

define eval_test_scene
# The levels below the last are written by the runs whose last images mark them (the radiance
# by trace's, the features by aov-write's: pipelines/dataset.mk).
$(filter-out $(call lx_image,$(EVAL_DATA)/$(1),$(NOISY_MAX),hdr),$(foreach s,$(NOISY_LEVELS),$(call lx_image,$(EVAL_DATA)/$(1),$(s),hdr))): $(call lx_image,$(EVAL_DATA)/$(1),$(NOISY_MAX),hdr) ;
$(filter-out $(call lx_image,$(EVAL_DATA)/$(1),$(NOISY_MAX),nrm),$(foreach k,$(LX_FEATURES),$(foreach s,$(NOISY_LEVELS),$(call lx_image,$(EVAL_DATA)/$(1),$(s),$(k))))): $(call lx_image,$(EVAL_DATA)/$(1),$(NOISY_MAX),nrm) ;

$(call lx_image_pattern,$(EVAL_DS)/$(1),dn): $(foreach k,hdr $(LX_FEATURES),$(call lx_image_pattern,$(EVAL_DATA)/$(1),$(k))) $(EVAL_MODEL) $(EVAL_MODEL_STAMP) $(DENOISE)
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(DENOISE) $$< --model $(EVAL_MODEL) -o $$@

$(call lx_le_pattern,$(EVAL_DS)/$(1),hdr): build/dataset/$(DATASET)/test/$(1).lxs $(ESTIMATE)
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(ESTIMATE) image $$< --paths $$* --seed $(NOISY_SEED) -o $$@

$(call lx_le_pattern,$(EVAL_DS)/$(1),dn): $(call lx_le_pattern,$(EVAL_DS)/$(1),hdr) $(call lx_features,$(EVAL_DATA)/$(1),$(NOISY_MAX)) $(EVAL_MODEL) $(EVAL_MODEL_STAMP) $(DENOISE)
	$$(LAUNCH) $$(DENOISE) $$< --model $(EVAL_MODEL) --features-of $(call lx_image,$(EVAL_DATA)/$(1),$(NOISY_MAX),hdr) -o $$@

$(call lx_image_pattern,$(EVAL_DS)/oidn/$(1)-oidn,dn): $(call lx_image_pattern,$(EVAL_DATA)/$(1),hdr) $(call lx_image_pattern,$(EVAL_DATA)/$(1),alb) $(call lx_image_pattern,$(EVAL_DATA)/$(1),nrm) pipelines/oidn_denoise.py
	@mkdir -p $$(@D)
	$(LAUNCH) $(OIDN_DENOISE) $$< --alb $$(word 2,$$^) --nrm $$(word 3,$$^) -o $$@

$(call lx_le_pattern,$(EVAL_DS)/oidn/$(1)-oidn,dn): $(call lx_le_pattern,$(EVAL_DS)/$(1),hdr) $(call lx_image,$(EVAL_DATA)/$(1),$(NOISY_MAX),alb) $(call lx_image,$(EVAL_DATA)/$(1),$(NOISY_MAX),nrm) pipelines/oidn_denoise.py
	@mkdir -p $$(@D)
	$(LAUNCH) $(OIDN_DENOISE) $$< --alb $$(word 2,$$^) --nrm $$(word 3,$$^) -o $$@

$(call lx_image_pattern,$(EVAL_DS)/oidn2/$(1)-oidn2,dn): $(call lx_image_pattern,$(EVAL_DATA)/$(1),hdr) $(call lx_image_pattern,$(EVAL_DATA)/$(1),alb) $(call lx_image_pattern,$(EVAL_DATA)/$(1),nrm) pipelines/oidn_denoise.py
	@mkdir -p $$(@D)
	$(LAUNCH) $(OIDN2_DENOISE) --aux $(OIDN2_AUX_ANTIALIASED) $$< --alb $$(word 2,$$^) --nrm $$(word 3,$$^) -o $$@

$(call lx_le_pattern,$(EVAL_DS)/oidn2/$(1)-oidn2,dn): $(call lx_le_pattern,$(EVAL_DS)/$(1),hdr) $(call lx_image,$(EVAL_DATA)/$(1),$(NOISY_MAX),alb) $(call lx_image,$(EVAL_DATA)/$(1),$(NOISY_MAX),nrm) pipelines/oidn_denoise.py
	@mkdir -p $$(@D)
	$(LAUNCH) $(OIDN2_DENOISE) --aux $(OIDN2_AUX_ANTIALIASED) $$< --alb $$(word 2,$$^) --nrm $$(word 3,$$^) -o $$@

$(EVAL_CSV)/dataset-$(1).images.csv: $(call eval_heldout_ref,$(1)) $(EVAL_HELDOUT_REF_STAMP) \
		$(foreach s,$(NOISY_LEVELS),$(call lx_image,$(EVAL_DATA)/$(1),$(s),hdr) $(call lx_image,$(EVAL_DS)/$(1),$(s),dn) $(call lx_image,$(EVAL_DS)/oidn/$(1)-oidn,$(s),dn) $(call if_oidn2,$(call lx_image,$(EVAL_DS)/oidn2/$(1)-oidn2,$(s),dn))) \
		$(foreach n,$(EVAL_DATA_DLE),$(call lx_le,$(EVAL_DS)/oidn/$(1)-oidn,$(n),dn) $(call if_oidn2,$(call lx_le,$(EVAL_DS)/oidn2/$(1)-oidn2,$(n),dn))) \
		$(foreach n,$(EVAL_DATA_DLE),$(call lx_le,$(EVAL_DS)/$(1),$(n),hdr) $(call lx_le,$(EVAL_DS)/$(1),$(n),dn)) $(EVALUATE)
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(EVALUATE) images --reference $$< $$(filter-out $$< $(EVALUATE) $(EVAL_HELDOUT_REF_STAMP),$$^) -o $$@ --ron $$(@:.csv=.ron)
endef
$(foreach n,$(EVAL_TEST_SCENES),$(eval $(call eval_test_scene,$(n))))

# (3) Sensors: the scenes of make validate (pipelines/validate.mk), fewer paths, own directory.
$(EVAL_DIR)/sensors/%.sensors.ron: $(VALIDATE_DIR)/%.lxs $(ESTIMATE) $(VALIDATE_DIR)/cases.mk
	@mkdir -p $(@D)
	$(LAUNCH) $(ESTIMATE) sensors $< -o $@ --paths $(EVAL_SENSOR_PATHS_$*) --seed $(NOISY_SEED)

$(EVAL_CSV)/sensors-%.csv: $(EVAL_DIR)/sensors/%.sensors.ron $(VALIDATE_DIR)/%.lxs $(EVALUATE)
	@mkdir -p $(@D)
	$(LAUNCH) $(EVALUATE) sensors $< --scene $(VALIDATE_DIR)/$*.lxs --case '$(VALIDATE_CASE_$*)' $(VALIDATE_EXTRA_$*) -o $@ --ron $(@:.csv=.ron)

# (4) The public interiors (scenes/public/<name>/scene.xml, imported by scene-compile): NAME=WxH
#    in EVAL_PUBLIC (their films' aspects, EVAL_PUBLIC_LONG pixels on the long side). Each: a
#    reference of EVAL_PUBLIC_REF_SPP spp (seed REF_SEED) and its albedo (the texture mask of
#    the summary, pipelines/eval.py), one progressive run (seed NOISY_SEED) with snapshots at
#    EVAL_PUBLIC_SPP, its features antialiased (FEATURE_SPP, beside it) and of each snapshot's own samples
#    (own-features/), double-local-estimate images at EVAL_PUBLIC_DLE paths denoised with the
#    last snapshot's antialiased features; every image denoised by luxest's model, OIDN 1.4.3 and
#    OIDN 2.5.1. Two reports a scene: public-<name>.images.csv (antialiased features, and the
#    double local estimate) and public-<name>-own-features.images.csv; FLIP maps under
#    $(EVAL_DIR)/flip/<report>/ (the summary's FLIP on textured regions reads them).
EVAL_PUBLIC ?= living-room=$(EVAL_PUBLIC_LONG)x$(EVAL_PUBLIC_SHORT) staircase=$(EVAL_PUBLIC_SHORT)x$(EVAL_PUBLIC_LONG)
EVAL_PUBLIC_NAMES := $(foreach p,$(EVAL_PUBLIC),$(firstword $(subst =, ,$(p))))
EVAL_PUBLIC_LAST := $(lastword $(EVAL_PUBLIC_SPP))
EVAL_PUB := $(EVAL_DIR)/public
eval_pub_scene = build/public/$(1)/scene.lxs

build/public/%/scene.lxs: scenes/public/%/scene.xml $(SCENE_COMPILE)
	@mkdir -p $(@D)
	$(LAUNCH) $(SCENE_COMPILE) $< -o $@ -q

define eval_public_scene
# $(1): the name, $(2): the resolution; P: the noisy run's prefix (antialiased features beside it).
$(eval P := $(EVAL_PUB)/$(1)/$(1))
$(eval DF := $(EVAL_PUB)/$(1)/own-features/$(1))
build/public/$(1)/scene.lxs: $(shell find scenes/public/$(1) -type f -not -name '*.xml' -not -name '* *' 2>/dev/null)

$(call lx_ref,$(P),hdr): $(call eval_pub_scene,$(1)) $(TRACE)
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(TRACE) $$< --spp $(EVAL_PUBLIC_REF_SPP) --reference --seed $(REF_SEED) --resolution $(2) -o $(P)

$(call lx_ref,$(P),alb): $(call eval_pub_scene,$(1)) $(AOV_WRITE)
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(AOV_WRITE) $$< --spp $(EVAL_PUBLIC_LAST) --reference --min-samples $(EVAL_PUBLIC_LAST) --seed $(REF_SEED) --resolution $(2) -o $(P)

$(call lx_image,$(P),$(EVAL_PUBLIC_LAST),hdr): $(call eval_pub_scene,$(1)) $(TRACE)
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(TRACE) $$< --spp $(EVAL_PUBLIC_LAST) --snapshots $(subst $(space),$(comma),$(EVAL_PUBLIC_SPP)) --seed $(NOISY_SEED) --resolution $(2) -o $(P)
$(filter-out $(call lx_image,$(P),$(EVAL_PUBLIC_LAST),hdr),$(foreach s,$(EVAL_PUBLIC_SPP),$(call lx_image,$(P),$(s),hdr))): $(call lx_image,$(P),$(EVAL_PUBLIC_LAST),hdr) ;

$(call lx_image,$(P),$(EVAL_PUBLIC_LAST),nrm): $(call eval_pub_scene,$(1)) $(AOV_WRITE) $(call lx_stamp,$(EVAL_DIR),feature-spp,$(FEATURE_SPP))
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(AOV_WRITE) $$< --spp $(EVAL_PUBLIC_LAST) --snapshots $(subst $(space),$(comma),$(EVAL_PUBLIC_SPP)) --seed $(NOISY_SEED) --min-samples $(FEATURE_SPP) --resolution $(2) -o $(P)
$(filter-out $(call lx_image,$(P),$(EVAL_PUBLIC_LAST),nrm),$(foreach k,$(LX_FEATURES),$(foreach s,$(EVAL_PUBLIC_SPP),$(call lx_image,$(P),$(s),$(k))))): $(call lx_image,$(P),$(EVAL_PUBLIC_LAST),nrm) ;

$(call lx_image,$(DF),$(EVAL_PUBLIC_LAST),nrm): $(call eval_pub_scene,$(1)) $(AOV_WRITE)
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(AOV_WRITE) $$< --spp $(EVAL_PUBLIC_LAST) --snapshots $(subst $(space),$(comma),$(EVAL_PUBLIC_SPP)) --seed $(NOISY_SEED) --min-samples 1 --resolution $(2) -o $(DF)
$(filter-out $(call lx_image,$(DF),$(EVAL_PUBLIC_LAST),nrm),$(foreach k,$(LX_FEATURES),$(foreach s,$(EVAL_PUBLIC_SPP),$(call lx_image,$(DF),$(s),$(k))))): $(call lx_image,$(DF),$(EVAL_PUBLIC_LAST),nrm) ;

$(call lx_le_pattern,$(P),hdr): $(call eval_pub_scene,$(1)) $(ESTIMATE)
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(ESTIMATE) image $$< --paths $$* --seed $(NOISY_SEED) --resolution $(2) -o $$@

# luxest's model: antialiased features beside the image; the own-sample ones through --features-of.
$(call lx_image_pattern,$(P),dn): $(foreach k,hdr $(LX_FEATURES),$(call lx_image_pattern,$(P),$(k))) $(EVAL_MODEL) $(EVAL_MODEL_STAMP) $(DENOISE)
	$$(LAUNCH) $$(DENOISE) $$< --model $(EVAL_MODEL) -o $$@
$(call lx_image_pattern,$(DF)-df,dn): $(call lx_image_pattern,$(P),hdr) $(foreach k,$(LX_FEATURES),$(call lx_image_pattern,$(DF),$(k))) $(EVAL_MODEL) $(EVAL_MODEL_STAMP) $(DENOISE)
	$$(LAUNCH) $$(DENOISE) $$< --model $(EVAL_MODEL) --any-feature-samples --features-of $(DF)_$$*spp.hdr.exr -o $$@
$(call lx_le_pattern,$(P),dn): $(call lx_le_pattern,$(P),hdr) $(call lx_features,$(P),$(EVAL_PUBLIC_LAST)) $(EVAL_MODEL) $(EVAL_MODEL_STAMP) $(DENOISE)
	$$(LAUNCH) $$(DENOISE) $$< --model $(EVAL_MODEL) --features-of $(call lx_image,$(P),$(EVAL_PUBLIC_LAST),hdr) -o $$@

# The peers, on the same inputs and features.
$(call lx_image_pattern,$(EVAL_PUB)/$(1)/oidn/$(1)-oidn,dn): $(foreach k,hdr alb nrm,$(call lx_image_pattern,$(P),$(k))) pipelines/oidn_denoise.py
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(OIDN_DENOISE) $$< --alb $$(word 2,$$^) --nrm $$(word 3,$$^) -o $$@
$(call lx_image_pattern,$(EVAL_PUB)/$(1)/oidn2/$(1)-oidn2,dn): $(foreach k,hdr alb nrm,$(call lx_image_pattern,$(P),$(k))) pipelines/oidn_denoise.py
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(OIDN2_DENOISE) --aux $(OIDN2_AUX_ANTIALIASED) $$< --alb $$(word 2,$$^) --nrm $$(word 3,$$^) -o $$@
$(call lx_image_pattern,$(DF)-df-oidn,dn): $(call lx_image_pattern,$(P),hdr) $(call lx_image_pattern,$(DF),alb) $(call lx_image_pattern,$(DF),nrm) pipelines/oidn_denoise.py
	$$(LAUNCH) $$(OIDN_DENOISE) $$< --alb $$(word 2,$$^) --nrm $$(word 3,$$^) -o $$@
$(call lx_image_pattern,$(DF)-df-oidn2,dn): $(call lx_image_pattern,$(P),hdr) $(call lx_image_pattern,$(DF),alb) $(call lx_image_pattern,$(DF),nrm) pipelines/oidn_denoise.py
	$$(LAUNCH) $$(OIDN2_DENOISE) --aux $(OIDN2_AUX_DEFAULT) $$< --alb $$(word 2,$$^) --nrm $$(word 3,$$^) -o $$@
$(call lx_le_pattern,$(EVAL_PUB)/$(1)/oidn/$(1)-oidn,dn): $(call lx_le_pattern,$(P),hdr) $(call lx_image,$(P),$(EVAL_PUBLIC_LAST),alb) $(call lx_image,$(P),$(EVAL_PUBLIC_LAST),nrm) pipelines/oidn_denoise.py
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(OIDN_DENOISE) $$< --alb $$(word 2,$$^) --nrm $$(word 3,$$^) -o $$@
$(call lx_le_pattern,$(EVAL_PUB)/$(1)/oidn2/$(1)-oidn2,dn): $(call lx_le_pattern,$(P),hdr) $(call lx_image,$(P),$(EVAL_PUBLIC_LAST),alb) $(call lx_image,$(P),$(EVAL_PUBLIC_LAST),nrm) pipelines/oidn_denoise.py
	@mkdir -p $$(@D)
	$$(LAUNCH) $$(OIDN2_DENOISE) --aux $(OIDN2_AUX_ANTIALIASED) $$< --alb $$(word 2,$$^) --nrm $$(word 3,$$^) -o $$@

$(EVAL_CSV)/public-$(1).images.csv: $(call lx_ref,$(P),hdr) $(call lx_ref,$(P),alb) \
		$(foreach s,$(EVAL_PUBLIC_SPP),$(call lx_image,$(P),$(s),hdr) $(call lx_image,$(P),$(s),dn) $(call lx_image,$(EVAL_PUB)/$(1)/oidn/$(1)-oidn,$(s),dn) $(call if_oidn2,$(call lx_image,$(EVAL_PUB)/$(1)/oidn2/$(1)-oidn2,$(s),dn))) \
		$(foreach n,$(EVAL_PUBLIC_DLE),$(call lx_le,$(P),$(n),hdr) $(call lx_le,$(P),$(n),dn) $(call lx_le,$(EVAL_PUB)/$(1)/oidn/$(1)-oidn,$(n),dn) $(call if_oidn2,$(call lx_le,$(EVAL_PUB)/$(1)/oidn2/$(1)-oidn2,$(n),dn))) $(EVALUATE)
	@mkdir -p $$(@D) $(EVAL_DIR)/flip/public-$(1)
	$$(LAUNCH) $$(EVALUATE) images --reference $$< $$(filter-out $$< $$(word 2,$$^) $$(EVALUATE),$$^) -o $$@ --ron $$(@:.csv=.ron) --flip-maps $(EVAL_DIR)/flip/public-$(1)

$(EVAL_CSV)/public-$(1)-own-features.images.csv: $(call lx_ref,$(P),hdr) $(call lx_ref,$(P),alb) \
		$(foreach s,$(EVAL_PUBLIC_SPP),$(call lx_image,$(P),$(s),hdr) $(call lx_image,$(DF)-df,$(s),dn) $(call lx_image,$(DF)-df-oidn,$(s),dn) $(call if_oidn2,$(call lx_image,$(DF)-df-oidn2,$(s),dn))) $(EVALUATE)
	@mkdir -p $$(@D) $(EVAL_DIR)/flip/public-$(1)-own-features
	$$(LAUNCH) $$(EVALUATE) images --reference $$< $$(filter-out $$< $$(word 2,$$^) $$(EVALUATE),$$^) -o $$@ --ron $$(@:.csv=.ron) --flip-maps $(EVAL_DIR)/flip/public-$(1)-own-features
endef
$(foreach p,$(EVAL_PUBLIC),$(eval $(call eval_public_scene,$(firstword $(subst =, ,$(p))),$(lastword $(subst =, ,$(p))))))
EVAL_PUBLIC_REPORTS := $(foreach n,$(EVAL_PUBLIC_NAMES),$(EVAL_CSV)/public-$(n).images.csv $(EVAL_CSV)/public-$(n)-own-features.images.csv)

# The summary: tables and plots from the reports (pipelines/eval.py summary).
EVAL_REPORTS := $(EVAL_CSV)/cornell-box.images.csv $(EVAL_CSV)/cornell-box-own-features.images.csv \
	$(patsubst %,$(EVAL_CSV)/dataset-%.images.csv,$(EVAL_TEST_SCENES)) $(EVAL_PUBLIC_REPORTS) \
	$(patsubst %,$(EVAL_CSV)/sensors-%.csv,$(VALIDATE_CASES))

$(REPORTS)/summary.md: $(EVAL_REPORTS) pipelines/eval.py python/luxest_contract.py $(VENV)/$(VENV_STAMP)
	$(PYTHON) pipelines/eval.py summary --reports $(REPORTS) --preset $(PRESET) --model $(EVAL_MODEL) \
		--cornell $(EVAL_CSV)/cornell-box.images.csv --cornell-own-features $(EVAL_CSV)/cornell-box-own-features.images.csv \
		--dataset $(filter $(EVAL_CSV)/dataset-%,$^) --public $(filter $(EVAL_CSV)/public-%,$^) --flip-dir $(EVAL_DIR)/flip \
		--public-ref-spp $(EVAL_PUBLIC_REF_SPP) \
		--sensors $(filter $(EVAL_CSV)/sensors-%,$^) \
		--ref-spp $(EVAL_REF_SPP) --ref-seed $(REF_SEED) --noisy-seed $(NOISY_SEED) \
		--dataset-ref-spp $(EVAL_HELDOUT_REF_SPP) --sensor-scale $(EVAL_SENSOR_SCALE)

eval: $(REPORTS)/summary.md
