#!/usr/bin/env python3
"""Writes the textures of the example interior, scenes/textured-room.ron, into scenes/textures/
(standard library only): images of the procedural library data-gen/textures.py, at sizes that
keep the checked-in files small (about 180 KB in all). Re-running reproduces them byte for byte (with the same zlib).

  floor  wood-planks                 walls     plaster          rug and sofa  fabric
  table  marble                      picture   photo-still-life  notice        paper-text (256 px)
  window photo-landscape (emitting)  plant     leaves (cut-out)  vent          grille (cut-out)
"""

from pathlib import Path

import textures

OUT = Path(__file__).resolve().parent.parent / "scenes" / "textures"
SEED = 1
# Side in pixels of each image: the page, read closely, gets more.
SIDES = {
    "wood-planks": 128,
    "paper-text": 256,
    "plaster": 128,
    "fabric": 128,
    "marble": 128,
    "photo-still-life": 128,
    "photo-landscape": 128,
    "leaves": 128,
    "grille": 128,
}

if __name__ == "__main__":
    for name, side in SIDES.items():
        (path,) = textures.write_library(OUT, side, SEED, names=(name,))
        print(f"wrote {path} ({path.stat().st_size} bytes)")
