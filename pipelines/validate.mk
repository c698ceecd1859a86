# `make validate`: the local estimate against exact solutions, path tracing against the exact
# luminance inside the integrating sphere, the direct-simulation baseline, and the goniometric
# luminaire cases (a cosⁿ IES file over a plane, between two planes, in the sphere). One rule per
# output file in $(VALIDATE_DIR); pipelines/validate.py defines the cases, writes the scene
# variants, checks the traced pixels and writes the summary (fails if any |z| > 4). Every stage
# is called through its variable. Incremental and parallel (`make -j2 validate`).

VALIDATE_DIR := build/validate/$(PRESET)
VALIDATE_SEED := 1
VALIDATE_TRACE_SPP := 1024

# The cases as Make variables (VALIDATE_CASES, VALIDATE_PATHS_<case>, ...), from validate.py.
$(VALIDATE_DIR)/cases.mk: pipelines/validate.py pipelines/presets.mk
	@mkdir -p $(@D)
	@python3 pipelines/validate.py cases --scale $(VALIDATE_SCALE) --eval-scale $(EVAL_SENSOR_SCALE) -o $@
include $(VALIDATE_DIR)/cases.mk

$(VALIDATE_DIR)/%.scene.ron: pipelines/validate.py scenes/integrating-sphere.ron
	python3 pipelines/validate.py scene $* -o $@

$(VALIDATE_DIR)/%.lxs: $(VALIDATE_DIR)/%.scene.ron $(SCENE_COMPILE)
	$(LAUNCH) $(SCENE_COMPILE) $< -o $@ -q

$(VALIDATE_DIR)/%.sensors.ron: $(VALIDATE_DIR)/%.lxs $(ESTIMATE) $(VALIDATE_DIR)/cases.mk
	$(LAUNCH) $(ESTIMATE) sensors $< -o $@ --paths $(VALIDATE_PATHS_$*) --seed $(VALIDATE_SEED)

$(VALIDATE_DIR)/%.exact.csv: $(VALIDATE_DIR)/%.sensors.ron $(EVALUATE)
	$(LAUNCH) $(EVALUATE) sensors $< --case '$(VALIDATE_CASE_$*)' $(VALIDATE_EXTRA_$*) -o $@

# Path tracing inside the sphere with a central source (its scene has a camera inside).
$(call lx_image,$(VALIDATE_DIR)/trace-sphere-rho%,$(VALIDATE_TRACE_SPP),hdr): $(VALIDATE_DIR)/trace-sphere-rho%.lxs $(TRACE)
	$(LAUNCH) $(TRACE) $< --spp $(VALIDATE_TRACE_SPP) --stderr --seed $(VALIDATE_SEED) -o $(VALIDATE_DIR)/trace-sphere-rho$*

$(VALIDATE_DIR)/trace-sphere-rho%.check.json: $(call lx_image,$(VALIDATE_DIR)/trace-sphere-rho%,$(VALIDATE_TRACE_SPP),hdr) pipelines/validate.py
	$(PYTHON) pipelines/validate.py trace-check --rho $* --hdr $< --se $(call lx_image,$(VALIDATE_DIR)/trace-sphere-rho$*,$(VALIDATE_TRACE_SPP),se) -o $@

# The direct simulation against the local estimate on the default Sobolev problem (own seeds).
VALIDATE_DIRECT_SCENE := $(VALIDATE_DIR)/sobolev-h1.0-1.0-rho0.5-0.5.lxs
VALIDATE_DIRECT_PATHS := 1000000

$(VALIDATE_DIR)/le.sensors.ron: $(VALIDATE_DIRECT_SCENE) $(ESTIMATE)
	$(LAUNCH) $(ESTIMATE) sensors $< -o $@ --paths $(VALIDATE_DIRECT_PATHS) --seed 2

$(VALIDATE_DIR)/le.exact.csv: $(VALIDATE_DIR)/le.sensors.ron $(EVALUATE)
	$(LAUNCH) $(EVALUATE) sensors $< --case '$(VALIDATE_DIRECT_CASE)' -o $@

$(VALIDATE_DIR)/direct-b%.sensors.ron: $(VALIDATE_DIRECT_SCENE) $(ESTIMATE)
	$(LAUNCH) $(ESTIMATE) direct $< -o $@ --paths $(VALIDATE_DIRECT_PATHS) --bin-radius $* --seed 3

$(VALIDATE_DIR)/direct-b%.exact.csv: $(VALIDATE_DIR)/direct-b%.sensors.ron $(EVALUATE)
	$(LAUNCH) $(EVALUATE) sensors $< --case '$(VALIDATE_DIRECT_CASE),bin=$*' -o $@

# The cosⁿ luminaire over a black plane: the direct simulation (sampled emission) against the
# closed-form direct illuminance (the local estimate computes that term deterministically).
$(VALIDATE_DIR)/cosn-plane.sensors.ron: $(VALIDATE_DIR)/cosn-plane.lxs $(ESTIMATE) $(VALIDATE_DIR)/cases.mk
	$(LAUNCH) $(ESTIMATE) direct $< -o $@ --paths $(VALIDATE_COSN_PLANE_PATHS) --bin-radius $(VALIDATE_COSN_PLANE_BIN) --seed $(VALIDATE_SEED)

VALIDATE_OUTPUTS := $(patsubst %,$(VALIDATE_DIR)/%.exact.csv,$(VALIDATE_CASES) le cosn-plane $(addprefix direct-b,$(VALIDATE_DIRECT_BINS))) \
	$(patsubst %,$(VALIDATE_DIR)/trace-sphere-rho%.check.json,$(VALIDATE_TRACE_RHOS))

# The summary runs every time (it is cheap) and fails the target if any case fails.
validate: $(VALIDATE_OUTPUTS) $(VENV)/$(VENV_STAMP)
	$(PYTHON) pipelines/validate.py summary --dir $(VALIDATE_DIR) -o $(VALIDATE_DIR)/summary.md
