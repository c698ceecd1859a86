# `make singularity`: the kernel regularisation at the Cornell box's corner and edge sensors
# (pipelines/singularity.py defines the runs and writes the summary). One rule per output file in
# $(SINGULARITY_DIR); incremental and parallel (`make -j2 singularity`; the seconds it reports
# are then contended).

SINGULARITY_DIR := build/singularity/$(PRESET)

$(SINGULARITY_DIR)/runs.mk: pipelines/singularity.py
	@mkdir -p $(@D)
	@python3 pipelines/singularity.py runs -o $@
include $(SINGULARITY_DIR)/runs.mk

$(SINGULARITY_DIR)/cornell-corners.scene.ron: pipelines/singularity.py scenes/cornell-box.ron
	python3 pipelines/singularity.py scene -o $@

$(SINGULARITY_DIR)/cornell-corners.lxs: $(SINGULARITY_DIR)/cornell-corners.scene.ron $(SCENE_COMPILE)
	$(LAUNCH) $(SCENE_COMPILE) $< -o $@ -q

# The reference: the backward gather estimator at the same points (own seed).
$(SINGULARITY_DIR)/gather.sensors.ron: $(SINGULARITY_DIR)/cornell-corners.lxs $(ESTIMATE)
	$(LAUNCH) $(ESTIMATE) gather $< -o $@ --csv $(@:.ron=.csv) --samples $(SINGULARITY_SAMPLES) --seed 11

$(SINGULARITY_DIR)/le-%.sensors.ron: $(SINGULARITY_DIR)/cornell-corners.lxs $(ESTIMATE) $(SINGULARITY_DIR)/runs.mk
	$(LAUNCH) $(ESTIMATE) sensors $< -o $@ --csv $(@:.ron=.csv) --paths $(SINGULARITY_PATHS) --seed 12 $(SINGULARITY_ARGS_le-$*)

singularity: $(patsubst %,$(SINGULARITY_DIR)/%.sensors.ron,gather $(SINGULARITY_RUNS)) $(VENV)/$(VENV_STAMP)
	$(PYTHON) pipelines/singularity.py summary --dir $(SINGULARITY_DIR) -o $(SINGULARITY_DIR)/summary.md
