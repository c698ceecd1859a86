# `make lighting`: the lighting report of the example office, one rule per output
# file. Compile the scene, print its header (calculation grids, luminaires), estimate the work
# plane by the local estimate, and write reports/lighting/office/ with the `report` stage:
# report.md, work-plane.csv/.ron and work-plane.isolux.png. The Radiance results committed
# beside it (radiance.csv) are compared point by point when present; `make lighting-radiance`
# recomputes them (needs `scripts/setup.sh --peers`). Every stage is called through its variable.

LIGHTING_SCENE ?= office
LIGHTING_BUILD := build/$(LIGHTING_SCENE)
LIGHTING_DIR ?= reports/lighting/$(LIGHTING_SCENE)
# Light paths: 1M gives about 0.04 % relative standard error on Eavg, 0.1 % on Emin and U0, in
# about 5 s on 2 cores (200k already gives <= 0.25 %; docs/measurements.md).
LIGHTING_PATHS ?= 1000000
LIGHTING_SEED ?= 1
LIGHTING_PEER := $(wildcard $(LIGHTING_DIR)/radiance.csv)
PEERS_PYTHON ?= .venv-peers/bin/python

.PHONY: lighting lighting-radiance

lighting: $(LIGHTING_DIR)/report.md

# The compiled scene embeds the photometric tables: recompile when a file changes.
$(LIGHTING_BUILD)/scene.lxs: $(wildcard scenes/photometry/*.ies scenes/photometry/*.ldt)

$(LIGHTING_BUILD)/scene.info.ron: $(LIGHTING_BUILD)/scene.lxs $(SCENE_COMPILE)
	$(LAUNCH) $(SCENE_COMPILE) --info $< > $@.tmp && mv $@.tmp $@

$(LIGHTING_BUILD)/$(LIGHTING_SCENE).sensors.ron: $(LIGHTING_BUILD)/scene.lxs $(ESTIMATE)
	$(LAUNCH) $(ESTIMATE) sensors $< -o $@ --paths $(LIGHTING_PATHS) --seed $(LIGHTING_SEED) --batch-values

$(LIGHTING_DIR)/report.md: $(LIGHTING_BUILD)/$(LIGHTING_SCENE).sensors.ron $(LIGHTING_BUILD)/scene.info.ron $(REPORT) $(LIGHTING_PEER)
	$(LAUNCH) $(REPORT) $< --scene-info $(LIGHTING_BUILD)/scene.info.ron -o $(LIGHTING_DIR) $(if $(LIGHTING_PEER),--peer $(LIGHTING_PEER))

# The peer: Radiance (rtrace -I) on the same room, luminaire tables and points.
lighting-radiance: $(LIGHTING_BUILD)/scene.info.ron pipelines/radiance_office.py
	@test -x $(PEERS_PYTHON) || { echo "error: $(PEERS_PYTHON) not found: run scripts/setup.sh --no-python --no-ort --peers" >&2; exit 1; }
	$(PEERS_PYTHON) pipelines/radiance_office.py --scene scenes/$(LIGHTING_SCENE).ron \
		--info $< -o $(LIGHTING_DIR)/radiance.csv
	$(MAKE) lighting
