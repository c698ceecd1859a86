"""Compares a `trace` image of `scene.ron` (environment map, spot light) with Mitsuba 3's render
of the same scene as `scene-compile --export-mitsuba` writes it: image means and a z-test on
6 x 6 pixel blocks (trace's per-pixel standard errors; Mitsuba's taken as equal at equal spp).

    scene-compile scene.ron -o s.lxs --export-mitsuba mi
    trace s.lxs --spp 1024 --stderr -o t
    python compare_mitsuba.py mi/scene.xml t_001024spp.hdr.exr t_001024spp.se.exr 1024

`sky.exr` is the 32 x 16 map this scene reads (a gradient, a bright "sun" texel).
"""

import sys

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")


def luminance(a: np.ndarray) -> np.ndarray:
    return a[..., 0] * 0.2126 + a[..., 1] * 0.7152 + a[..., 2] * 0.0722


def main(xml: str, trace_exr: str, se_exr: str, spp: int) -> None:
    scene = mi.load_file(xml)
    ym = luminance(np.array(mi.render(scene, spp=spp, seed=3)))
    yt = luminance(np.array(mi.Bitmap(trace_exr))[:, :, :3])
    se = np.array(mi.Bitmap(se_exr))[:, :, 0]
    se_mean = np.sqrt((se**2).sum()) / se.size
    print(f"mean: trace {yt.mean():.6g} ± {se_mean:.2g}, mitsuba {ym.mean():.6g}, ratio {yt.mean() / ym.mean():.6f}")
    z = []
    for by in range(0, yt.shape[0], 6):
        for bx in range(0, yt.shape[1], 6):
            a, b = yt[by : by + 6, bx : bx + 6], ym[by : by + 6, bx : bx + 6]
            s = np.sqrt((se[by : by + 6, bx : bx + 6] ** 2).sum()) / a.size
            z.append((a.mean() - b.mean()) / max(np.sqrt(2.0) * s, 1e-30))
    z = np.array(z)
    print(f"{len(z)} blocks: max |z| {np.abs(z).max():.3g}, mean z {z.mean():.3g}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]))
