"""Reference table of Mitsuba 3's `envmap` radiance for luxest's environment lookup.

Writes `envmap_test.exr` (an 8 x 5 map whose texels are all distinct) and
`envmap_mitsuba.csv`: for 64 directions, the radiance Mitsuba 3 (`scalar_rgb`) returns for a
ray travelling along the direction that leaves the scene (`eval` with `wi = -d`), with a
rotated `to_world` and a `scale`. The test `environment::tests::lookup_agrees_with_mitsuba`
reads both. Run from the repository root:

    .venv-peers/bin/python crates/render/tests/data/envmap_mitsuba.py
"""

from pathlib import Path

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

HERE = Path(__file__).resolve().parent
WIDTH, HEIGHT = 8, 5
SCALE = 1.7
# Mitsuba's `rotate` expects a unit axis.
AXIS, ANGLE_DEG = list(np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])), 40.0


def texels() -> np.ndarray:
    t = np.zeros((HEIGHT, WIDTH, 3), dtype=np.float32)
    for j in range(HEIGHT):
        for i in range(WIDTH):
            v = 1.0 + i + 10.0 * j
            t[j, i] = (v, 2.0 * v + 1.0, 0.5 * v + 3.0 * (i % 3))
    return t


def directions() -> np.ndarray:
    rng = np.random.default_rng(47)
    d = rng.normal(size=(56, 3))
    special = [
        (0, 1, 0),  # the +y pole
        (0, -1, 0),  # the -y pole
        (0, 0, -1),  # u = 0 (the seam)
        (1e-3, 0.2, -1),  # just across the seam
        (-1e-3, 0.2, -1),
        (1, 0, 0),
        (0, 0, 1),
        (-1, 0.5, 0.3),
    ]
    d = np.concatenate([d, np.array(special, dtype=float)])
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def main() -> None:
    exr = HERE / "envmap_test.exr"
    mi.Bitmap(texels(), pixel_format=mi.Bitmap.PixelFormat.RGB).write(str(exr))
    to_world = mi.ScalarTransform4f().rotate(AXIS, ANGLE_DEG)
    emitter = mi.load_dict({"type": "envmap", "filename": str(exr), "scale": SCALE, "to_world": to_world})
    m = np.array(to_world.matrix)[:3, :3]
    lines = [
        "# Mitsuba 3 envmap radiance (scalar_rgb) along escaping rays; written by envmap_mitsuba.py",
        f"# mitsuba {mi.__version__}; map {exr.name}, scale {SCALE}",
        "# to_world row-major: " + " ".join(f"{x:.17g}" for x in m.flatten()),
        "dx,dy,dz,r,g,b",
    ]
    for d in directions():
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(-d)
        c = emitter.eval(si)
        lines.append(",".join(f"{x:.9g}" for x in [*d, c[0], c[1], c[2]]))
    (HERE / "envmap_mitsuba.csv").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
