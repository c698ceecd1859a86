# `make lighting`: the lighting reports of the example rooms, one rule per output file. For each
# scene of LIGHTING_SCENES (the office and the daylit room):
# compile it, print its header (calculation grids and their requirements, luminaires), estimate
# its calculation surfaces (and observers' glare, the sky's daylight) by the local estimate,
# render its luminance image by the double local estimate for the report's false-colour picture, and write
# reports/lighting/<scene>/ with the `report` stage: report.html (self-contained, what a
# designer signs), report.md (the same tables, for diffs), per surface <surface>.csv/.ron and
# <surface>.isolux.png, and luminance.png. Radiance results committed beside a report
# (radiance.csv) are compared point by point when present; `make lighting-radiance` recomputes
# them for LIGHTING_SCENE (needs `scripts/setup.sh --peers`). Every stage is called through its
# variable.

LIGHTING_SCENE ?= office
# The example rooms: the office and the daylit room (daylit-room), whichever of the two scenes/
# holds.
LIGHTING_SCENES ?= $(filter office daylit-room,$(basename $(notdir $(wildcard scenes/*.ron))))
# Light paths: 1M gives about 0.04 % relative standard error on Eavg, 0.1 % on Emin and U0, in
# about 5 s on 2 cores (200k already gives <= 0.25 %; docs/measurements.md).
LIGHTING_PATHS ?= 1000000
LIGHTING_SEED ?= 1
# The luminance image: the double local estimate (`estimate image`) with this many light paths,
# at the scene camera's resolution: 3 % median relative standard error per pixel on the office
# in about 5 CPU seconds, where `trace` at 64 spp gives 9 % in 7 (docs/measurements.md, *The
# lighting report's luminance image*).
LIGHTING_IMAGE_PATHS ?= 300
PEERS_PYTHON ?= .venv-peers/bin/python

.PHONY: lighting lighting-radiance

lighting: $(foreach s,$(LIGHTING_SCENES),reports/lighting/$(s)/report.md reports/lighting/$(s)/report.html)

# The compiled scene embeds the photometric tables: recompile when a file changes.
$(LIGHTING_SCENES:%=build/%/scene.lxs): $(wildcard scenes/photometry/*.ies scenes/photometry/*.ldt)

# One scene's rules ($(1): its name); the report's two documents are one recipe's outputs.
define lighting_rules
build/$(1)/scene.info.ron: build/$(1)/scene.lxs $$(SCENE_COMPILE)
	$$(LAUNCH) $$(SCENE_COMPILE) --info $$< > $$@.tmp && mv $$@.tmp $$@

build/$(1)/$(1).sensors.ron: build/$(1)/scene.lxs $$(ESTIMATE)
	$$(LAUNCH) $$(ESTIMATE) sensors $$< -o $$@ --paths $$(LIGHTING_PATHS) --seed $$(LIGHTING_SEED) --batch-values

build/$(1)/$(1)-luminance_$$(shell printf %06d $$(LIGHTING_IMAGE_PATHS))le.hdr.exr: build/$(1)/scene.lxs $$(ESTIMATE)
	$$(LAUNCH) $$(ESTIMATE) image $$< --paths $$(LIGHTING_IMAGE_PATHS) --seed $$(LIGHTING_SEED) -o $$@

reports/lighting/$(1)/report.md reports/lighting/$(1)/report.html &: build/$(1)/$(1).sensors.ron build/$(1)/scene.info.ron build/$(1)/$(1)-luminance_$$(shell printf %06d $$(LIGHTING_IMAGE_PATHS))le.hdr.exr $$(REPORT) $$(wildcard reports/lighting/$(1)/radiance.csv)
	$$(LAUNCH) $$(REPORT) $$< --scene-info build/$(1)/scene.info.ron --luminance $$(word 3,$$^) -o reports/lighting/$(1) $$(if $$(wildcard reports/lighting/$(1)/radiance.csv),--peer reports/lighting/$(1)/radiance.csv)
endef
$(foreach s,$(sort $(LIGHTING_SCENES) $(LIGHTING_SCENE)),$(eval $(call lighting_rules,$(s))))

# The peer: Radiance (rtrace -I) on the same room, luminaire tables and points.
lighting-radiance: build/$(LIGHTING_SCENE)/scene.info.ron pipelines/radiance_office.py
	@test -x $(PEERS_PYTHON) || { echo "error: $(PEERS_PYTHON) not found: run scripts/setup.sh --no-python --no-ort --peers" >&2; exit 1; }
	$(PEERS_PYTHON) pipelines/radiance_office.py --scene scenes/$(LIGHTING_SCENE).ron \
		--info $< -o reports/lighting/$(LIGHTING_SCENE)/radiance.csv
	$(MAKE) lighting LIGHTING_SCENES=$(LIGHTING_SCENE)

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
