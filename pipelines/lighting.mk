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

# `make lighting-glare`: UGR at the observers of the glare rooms (the office with its troffers
# and pendant, three pendants alone, bare round downlights) by luxest (`estimate sensors`) and by
# Radiance evalglare on rpict -vta fisheyes of the same rooms (pipelines/radiance_glare.py;
# needs `scripts/setup.sh --peers`): reports/lighting/glare/<scene>.md and .csv (committed; the
# CSV's evalglare numbers are what tests/glare.rs checks). `make ugr-tables` writes the CIE 190
# tables of the example luminaires and their independent check (pipelines/ugr_table_check.py).
GLARE_SCENES ?= office glare-pendants glare-downlights
GLARE_DIR ?= reports/lighting/glare
GLARE_PATHS ?= 200000
# Radiance settings of the committed reports (a 2-core machine shared by several jobs).
GLARE_RADIANCE ?= --res 300 --ab 3 --ad 256 --aa 0.2
UGR_TABLE_DIR ?= reports/lighting/ugr-table
UGR_LUMINAIRES ?= troffer-600-led.ies pendant-linear-4000.ldt downlight-150-round.ies

.PHONY: lighting-glare ugr-tables

lighting-glare: $(foreach s,$(GLARE_SCENES),$(GLARE_DIR)/$(s).md)

build/%/glare.sensors.ron: build/%/scene.lxs $(ESTIMATE)
	$(LAUNCH) $(ESTIMATE) sensors $< -o $@ --paths $(GLARE_PATHS) --seed 1

$(GLARE_DIR)/%.md: build/%/glare.sensors.ron build/%/scene.info.ron pipelines/radiance_glare.py
	@test -x $(PEERS_PYTHON) || { echo "error: $(PEERS_PYTHON) not found: run scripts/setup.sh --no-python --no-ort --peers" >&2; exit 1; }
	$(PEERS_PYTHON) pipelines/radiance_glare.py --scene scenes/$*.ron --info build/$*/scene.info.ron \
		--luxest $< -o $@ $(GLARE_RADIANCE)

build/%/scene.info.ron: build/%/scene.lxs $(SCENE_COMPILE)
	$(LAUNCH) $(SCENE_COMPILE) --info $< > $@.tmp && mv $@.tmp $@

ugr-tables: $(foreach f,$(UGR_LUMINAIRES),$(UGR_TABLE_DIR)/$(basename $(f)).csv $(UGR_TABLE_DIR)/$(basename $(f)).check.csv)

$(UGR_TABLE_DIR)/%.csv: $(REPORT)
	$(REPORT) ugr-table $(firstword $(wildcard scenes/photometry/$*.ies scenes/photometry/$*.ldt)) -o $@ > $(UGR_TABLE_DIR)/$*.txt

$(UGR_TABLE_DIR)/%.check.csv: pipelines/ugr_table_check.py
	$(PEERS_PYTHON) pipelines/ugr_table_check.py $(firstword $(wildcard scenes/photometry/$*.ies scenes/photometry/$*.ldt)) -o $@
