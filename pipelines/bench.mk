# `make bench-pt` (part of `make bench`): speed at equal error of path tracing, light tracing and
# the double local estimate against Mitsuba 3's path and ptracer on the same scene in the same run (pipelines/bench_pt.py; the peer column when .venv-peers has Mitsuba:
# `scripts/setup.sh --no-python --no-ort --peers`). The reference has its own seed (REF_SEED)
# and many more samples (BENCH_REF_SPP); the table goes to build/bench/<scene>/pt.md.

BENCH_SCENE ?= $(DEFAULT_SCENE)
BENCH_RESOLUTION ?= 256x256
BENCH_DIR := build/bench/$(BENCH_SCENE)

.PHONY: bench-pt

$(call lx_ref,$(BENCH_DIR)/ref,hdr): build/$(BENCH_SCENE)/scene.lxs $(TRACE)
	$(TRACE) $< --reference --spp $(BENCH_REF_SPP) --resolution $(BENCH_RESOLUTION) --seed $(REF_SEED) -o $(BENCH_DIR)/ref

$(BENCH_DIR)/scene.xml: scenes/$(BENCH_SCENE).ron $(MESHES) $(SCENE_COMPILE)
	$(SCENE_COMPILE) $< -o $(BENCH_DIR)/scene.lxs --export-mitsuba $(BENCH_DIR) -q

$(BENCH_DIR)/pt.md: build/$(BENCH_SCENE)/scene.lxs $(call lx_ref,$(BENCH_DIR)/ref,hdr) $(BENCH_DIR)/scene.xml \
		$(TRACE) $(ESTIMATE) $(EVALUATE) pipelines/bench_pt.py pipelines/mitsuba_render.py $(VENV)/$(VENV_STAMP)
	$(PYTHON) pipelines/bench_pt.py --scene $< --reference $(word 2,$^) --mitsuba-scene $(word 3,$^) \
		--peers-python $(PEERS_PYTHON) --trace $(TRACE) --estimate $(ESTIMATE) --evaluate $(EVALUATE) \
		--resolution $(BENCH_RESOLUTION) --spp $(subst $(space),$(comma),$(BENCH_SPP)) \
		--lt-paths $(subst $(space),$(comma),$(BENCH_LT)) --dle-paths $(subst $(space),$(comma),$(BENCH_DLE)) \
		--work-dir $(BENCH_DIR)/runs -o $@

bench-pt: $(BENCH_DIR)/pt.md
