"""Renders a scene exported by `scene-compile --export-mitsuba` with Mitsuba 3 (the peer of
`make mitsuba-check` and of `make bench-pt`), and with --luxest and --summary compares it with a
luxest image of the same scene: whole-image and 4 x 4 block means of Y and of each channel, as
ratios Mitsuba / luxest. Runs in .venv-peers (`scripts/setup.sh --peers`); prints the CPU
seconds of loading and rendering the scene (JIT compilation included; Python and Mitsuba's
import excluded), alone as `cpu_seconds <s> wall_seconds <s> sample_count <n>` without --summary (the
sample count the sampler used: `stratified` and `multijitter` round it up to a square or a
product of near factors, `ldsampler` to a power of two)."""

import argparse
import os
import re
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
from luxest_contract import luminance  # noqa: E402


def read_exr(path):
    """R, G, B of an EXR file as float64 (H, W, 3), read with Mitsuba's own EXR reader."""
    import mitsuba as mi

    return np.array(mi.Bitmap(str(path)), dtype=np.float64)[..., :3]


SAMPLERS = ("independent", "stratified", "ldsampler", "multijitter")


def scene_xml(mi, path, resolution=None, integrator="path", sampler="independent"):
    """The text of an exported scene, with the film size `resolution` ("WxH"), `integrator` in
    place of the exported `path` and `sampler` in place of the exported `independent` when
    given; registers the scene's folder with Mitsuba's file resolver (meshes are named relative
    to the scene file)."""
    xml = open(path).read()
    if resolution:
        # The exporter writes the film size as literal integers: substitute them.
        w, h = (int(v) for v in resolution.split("x"))
        for name, v in (("width", w), ("height", h)):
            xml = re.sub(rf'(<integer name="{name}" value=")\d+(")', rf"\g<1>{v}\g<2>", xml, count=1)
    if integrator != "path":
        xml = xml.replace('<integrator type="path">', f'<integrator type="{integrator}">', 1)
    if sampler != "independent":
        if '<sampler type="independent">' not in xml:
            sys.exit(f'error: {path}: no <sampler type="independent"> to replace by {sampler}')
        xml = xml.replace('<sampler type="independent">', f'<sampler type="{sampler}">', 1)
    mi.file_resolver().prepend(os.path.dirname(os.path.abspath(path)))
    return xml


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", help="scene.xml written by scene-compile --export-mitsuba")
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--resolution", help="WIDTHxHEIGHT instead of the scene's")
    ap.add_argument(
        "--integrator",
        default="path",
        choices=["path", "ptracer"],
        help="the exported `path` (max_depth -1, rr_depth 5) or `ptracer` with the same settings",
    )
    ap.add_argument(
        "--sampler",
        default="independent",
        choices=SAMPLERS,
        help="the sensor's sampler, in place of the exported `independent`",
    )
    ap.add_argument("--luxest", help="a luxest image of the same scene (EXR), to compare with")
    ap.add_argument("-o", "--out", required=True, help="the Mitsuba image (EXR)")
    ap.add_argument("--summary", help="the comparison (Markdown; with --luxest)")
    a = ap.parse_args(argv)
    if (a.luxest is None) != (a.summary is None):
        sys.exit("error: --luxest and --summary go together")
    import mitsuba as mi

    mi.set_variant(a.variant)
    xml = scene_xml(mi, a.scene, a.resolution, a.integrator, a.sampler)
    import drjit as dr

    t, w = time.process_time(), time.time()
    scene = mi.load_string(xml, spp=a.spp)
    img = mi.render(scene, seed=a.seed)
    dr.eval(img)  # Dr.Jit is lazy: the render runs here
    dr.sync_thread()
    cpu, wall = time.process_time() - t, time.time() - w
    mi.util.write_bitmap(a.out, img, write_async=False)
    if a.luxest is None:
        spp = scene.sensors()[0].sampler().sample_count()
        print(f"cpu_seconds {cpu:.4f} wall_seconds {wall:.4f} sample_count {spp}")
        return
    m, lx = read_exr(a.out), read_exr(a.luxest)
    if m.shape != lx.shape:
        sys.exit(f"error: {a.luxest}: {lx.shape[1]}x{lx.shape[0]}, Mitsuba rendered {m.shape[1]}x{m.shape[0]}")
    y_m, y_l = luminance(m), luminance(lx)
    rows = [
        f"Mitsuba 3 `{a.variant}` `{a.integrator}` ({a.sampler}), {a.spp} spp: {cpu:.1f} CPU-s ({wall:.1f} s wall), against `{a.luxest}`.",
        "",
        "| region | Y ratio Mitsuba / luxest |",
        "|---|---|",
        f"| whole image | {y_m.mean() / y_l.mean():.4f} |",
    ]
    rows += [f"| channel {c} | {m[..., i].mean() / lx[..., i].mean():.4f} |" for i, c in enumerate("RGB")]
    h, w_ = m.shape[0] // 4, m.shape[1] // 4
    blocks = [
        y_m[i * h : (i + 1) * h, j * w_ : (j + 1) * w_].mean()
        / max(y_l[i * h : (i + 1) * h, j * w_ : (j + 1) * w_].mean(), 1e-300)
        for i in range(4)
        for j in range(4)
    ]
    rows += [f"| 4 x 4 blocks | {min(blocks):.4f} to {max(blocks):.4f} |", ""]
    text = "\n".join(rows)
    with open(a.summary, "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
