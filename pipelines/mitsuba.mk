# `make mitsuba-check`: the scene MITSUBA_SCENE (default: the default scene) exported for
# Mitsuba 3 by `scene-compile --export-mitsuba`, rendered by Mitsuba (`pipelines/mitsuba_render.py`
# in .venv-peers: `scripts/setup.sh --peers`) and by luxest's trace at the same resolution, and
# compared region by region (build/mitsuba/<scene>/check.md). A cross-check of any scene.

MITSUBA_SCENE ?= $(DEFAULT_SCENE)
MITSUBA_SPP ?= 256
MITSUBA_VARIANT ?= llvm_ad_rgb
MITSUBA_DIR := build/mitsuba/$(MITSUBA_SCENE)

.PHONY: mitsuba-check

$(MITSUBA_DIR)/scene.xml: scenes/$(MITSUBA_SCENE).ron $(MESHES) $(SCENE_COMPILE)
	$(LAUNCH) $(SCENE_COMPILE) $< -o $(MITSUBA_DIR)/scene.lxs --export-mitsuba $(MITSUBA_DIR) -q

$(call lx_image,$(MITSUBA_DIR)/luxest,$(MITSUBA_SPP),hdr): $(MITSUBA_DIR)/scene.xml $(TRACE)
	$(LAUNCH) $(TRACE) $(MITSUBA_DIR)/scene.lxs --spp $(MITSUBA_SPP) --seed $(REF_SEED) -o $(MITSUBA_DIR)/luxest

$(MITSUBA_DIR)/check.md: $(MITSUBA_DIR)/scene.xml $(call lx_image,$(MITSUBA_DIR)/luxest,$(MITSUBA_SPP),hdr) pipelines/mitsuba_render.py
	@test -x $(PEERS_PYTHON) || { echo "error: $(PEERS_PYTHON) missing: run scripts/setup.sh --peers" >&2; exit 1; }
	$(PEERS_PYTHON) pipelines/mitsuba_render.py $< --spp $(MITSUBA_SPP) --variant $(MITSUBA_VARIANT) \
		--luxest $(word 2,$^) -o $(MITSUBA_DIR)/mitsuba_$(call lx_count,$(MITSUBA_SPP))spp.exr --summary $@

mitsuba-check: $(MITSUBA_DIR)/check.md
