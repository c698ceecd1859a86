"""Loads the importer's test scenes with Mitsuba 3 (`mi.load_file`): each must be a valid
Mitsuba scene, so that the importer's tests check a translation of what Mitsuba itself reads.
Run with the peers' Python: `.venv-peers/bin/python crates/scene-compile/tests/data/mitsuba/check_with_mitsuba.py`."""

import glob
import os
import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")
here = os.path.dirname(os.path.abspath(__file__))
failed = 0
for path in sorted(glob.glob(os.path.join(here, "*.xml"))):
    try:
        scene = mi.load_file(path)
        print(
            f"ok {os.path.basename(path)}: {len(scene.shapes())} shapes, "
            f"{len(scene.emitters())} emitters, {len(scene.sensors())} sensors"
        )
    except Exception as e:  # noqa: BLE001 (report every scene)
        failed += 1
        print(f"FAILED {os.path.basename(path)}: {e}")
sys.exit(1 if failed else 0)
