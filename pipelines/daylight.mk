# `make lighting-daylight`: luxest's daylight against Radiance (needs scripts/setup.sh --peers).
# For each case (scene and tolerance): compile the scene, estimate its work plane by the local
# estimate (build/daylight/<scene>.sensors.ron), render the same room, sky and points with
# Radiance gensky + rtrace -I (reports/lighting/daylight/<scene>.radiance.csv, committed), and
# write the point-by-point comparison with the daylight-factor figures of both
# (reports/lighting/daylight/daylight.md, committed; pipelines/radiance_daylight.py). Cases: the
# daylit room with one and with two windows under the CIE overcast sky (2 % + 3σ at every
# point), and with two windows under the CIE clear sky with sun on 21 March, 12:00 CET, Berlin
# (3 % + 3σ).

DAYLIGHT_DIR ?= reports/lighting/daylight
# Light paths per case: 2M gives about 0.3 % standard error near the windows and 1–2 % at the
# back of the room.
DAYLIGHT_PATHS ?= 2000000
DAYLIGHT_SEED ?= 1
DAYLIGHT_CASES := daylit-room-one-window:0.02 daylit-room:0.02 daylit-room-sun:0.03
daylight_scene = $(word 1,$(subst :, ,$(1)))
daylight_tol = $(word 2,$(subst :, ,$(1)))

.PHONY: lighting-daylight

lighting-daylight: $(DAYLIGHT_DIR)/daylight.md

build/daylight/%.info.ron: build/%/scene.lxs $(SCENE_COMPILE)
	@mkdir -p $(@D)
	$(LAUNCH) $(SCENE_COMPILE) --info $< > $@.tmp && mv $@.tmp $@

build/daylight/%.sensors.ron: build/%/scene.lxs $(ESTIMATE)
	@mkdir -p $(@D)
	$(LAUNCH) $(ESTIMATE) sensors $< -o $@ --paths $(DAYLIGHT_PATHS) --seed $(DAYLIGHT_SEED)

# The peer depends on the scene and the script, not on luxest's binaries (the header only
# supplies the points).
$(DAYLIGHT_DIR)/%.radiance.csv: scenes/%.ron pipelines/radiance_daylight.py | build/daylight/%.info.ron
	@test -x $(PEERS_PYTHON) || { echo "error: $(PEERS_PYTHON) not found: run scripts/setup.sh --no-python --no-ort --peers" >&2; exit 1; }
	$(PEERS_PYTHON) pipelines/radiance_daylight.py --scene $< --info build/daylight/$*.info.ron -o $@

$(DAYLIGHT_DIR)/daylight.md: $(foreach c,$(DAYLIGHT_CASES),build/daylight/$(call daylight_scene,$(c)).sensors.ron $(DAYLIGHT_DIR)/$(call daylight_scene,$(c)).radiance.csv)
	$(PEERS_PYTHON) pipelines/radiance_daylight.py report --dir $(DAYLIGHT_DIR) \
		$(foreach c,$(DAYLIGHT_CASES),--case $(call daylight_scene,$(c)) build/daylight/$(call daylight_scene,$(c)).sensors.ron $(DAYLIGHT_DIR)/$(call daylight_scene,$(c)).radiance.csv $(call daylight_tol,$(c)))
