"""`make bench-scenes`: luxest's `trace` against Mitsuba 3 on Mitsuba 3 XML scenes, both loading the
same files in the same run. luxest imports each scene (`scene-compile scene.xml`) and path-traces
it; Mitsuba loads the same XML and renders it with its `path` integrator (`max_depth` −1, `rr_depth`
5: luxest's unbounded paths with Russian roulette), the film's reconstruction filter set to `box`
(luxest integrates over each pixel), in `REPS` independent runs whose spread gives Mitsuba's standard
errors. The images are compared as the validation compares exact cases: the whole-image mean of Y
and the means of 16 × 16 blocks, each difference divided by its standard error (z), with luxest's
standard errors from its own per-pixel estimates (`trace --stderr`). Every seed differs between the
two renderers and between Mitsuba's runs.

The scenes: the material and emitter scenes this script writes (every BSDF luxest imports, with
textures, a cut-out and a one-sided surface; meshes with vertex normals and normal maps; point,
spot, textured area, constant and map
environment emitters through a window), and any public scenes given with --scene NAME=PATH
(`scenes/public/*/scene.xml`: see its README for their authors and licences).

Runs in .venv-peers (Mitsuba 3, numpy); writes a Markdown report with the CPU seconds of both.
Standard library and numpy for the scenes it writes; deterministic."""

import argparse
import math
import re
import struct
import sys
import time
import zlib
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
from luxest_contract import image_name, luminance  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from atomic import write_text  # noqa: E402
from bench_pt import child_cpu  # noqa: E402
from host import host_summary  # noqa: E402
from mitsuba_render import read_exr  # noqa: E402

REPS = 8
BLOCKS = 16
LUXEST_SEED = 11
MITSUBA_SEED = 1000
# Relative rounding of f32 pixel values and their sums (a floor under noise-free blocks' errors).
F32_ROUNDING = 1e-6


# ---- scenes written by this script ---------------------------------------------------------


def png(path, w, h, pixels, channels=3):
    """An 8-bit PNG of `pixels` (rows of channel tuples, values 0..255)."""
    raw = b"".join(b"\x00" + bytes(v for px in row for v in px) for row in pixels)

    def chunk(kind, data):
        c = kind + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)

    colour = {1: 0, 3: 2, 4: 6}[channels]
    data = (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(raw, 9))
        + chunk(b"IEND", b"")
    )
    Path(path).write_bytes(data)


def exr_rgb(path, w, h, fn):
    """A linear EXR of fn(x, y) -> (r, g, b), written with Mitsuba's own writer."""
    import mitsuba as mi

    a = np.array([[fn(x, y) for x in range(w)] for y in range(h)], dtype=np.float32)
    mi.Bitmap(a).write(str(path))


def icosphere_obj(path, radius=1.0, level=2, normals=False):
    """An icosphere OBJ (flat-shaded by both renderers with `face_normals`; with `normals`, its
    radial vertex normals as `vn`, which both interpolate)."""
    t = (1 + 5**0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t)]
    verts += [(t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2)]
    faces += [(10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5)]
    faces += [(2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        cache, nxt = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = [(verts[a][i] + verts[b][i]) / 2 for i in range(3)]
                n = math.sqrt(sum(c * c for c in m))
                verts.append(tuple(c / n for c in m))
                cache[key] = len(verts) - 1
            return cache[key]

        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nxt += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = nxt
    lines = [f"v {v[0] * radius:.6f} {v[1] * radius:.6f} {v[2] * radius:.6f}" for v in verts]
    # Latitude-longitude texture coordinates (both renderers interpolate the same ones, seam
    # included).
    lines += [
        f"vt {0.5 + math.atan2(v[0], v[2]) / (2 * math.pi):.6f} {math.acos(max(-1, min(1, v[1]))) / math.pi:.6f}"
        for v in verts
    ]
    if normals:
        lines += [f"vn {v[0]:.6f} {v[1]:.6f} {v[2]:.6f}" for v in verts]
        lines += [f"f {a + 1}/{a + 1}/{a + 1} {b + 1}/{b + 1}/{b + 1} {c + 1}/{c + 1}/{c + 1}" for a, b, c in faces]
    else:
        lines += [f"f {a + 1}/{a + 1} {b + 1}/{b + 1} {c + 1}/{c + 1}" for a, b, c in faces]
    Path(path).write_text("\n".join(lines) + "\n")


def textures(d):
    """The scenes' textures: planks (sRGB PNG), a checker (PNG), a leaf-like cut-out mask (PNG
    with alpha), a lamp pattern (linear EXR) and a sky (EXR, brighter towards the zenith and a
    sun-like spot)."""
    n = 64
    png(
        d / "planks.png",
        n,
        n,
        [
            [
                tuple(
                    int(255 * c)
                    for c in ((0.55 + 0.15 * math.sin(y * 0.9 + (x // 16) * 1.7)) * s for s in (1, 0.7, 0.45))
                )
                for x in range(n)
            ]
            for y in range(n)
        ],
    )
    png(
        d / "checker.png",
        n,
        n,
        [[(220, 220, 220) if (x // 8 + y // 8) % 2 else (40, 60, 120) for x in range(n)] for y in range(n)],
    )
    png(
        d / "leaf.png",
        n,
        n,
        [
            [
                (60, 140, 50, 255 if (x - 32) ** 2 / 900 + (y - 32) ** 2 / 300 < 1 and (x + y) % 11 else 0)
                for x in range(n)
            ]
            for y in range(n)
        ],
        channels=4,
    )

    # A tangent-space normal map (raw): ridges along u and bumps, (n + 1) / 2 per channel.
    def bump(x, y):
        nx = -0.6 * math.cos(2 * math.pi * x / 16)
        ny = -0.35 * math.sin(2 * math.pi * (x + 2 * y) / 32)
        k = 1 / math.sqrt(nx * nx + ny * ny + 1)
        return tuple(round(255 * (c * k + 1) / 2) for c in (nx, ny, 1.0))

    png(d / "bumps.png", n, n, [[bump(x, y) for x in range(n)] for y in range(n)])
    exr_rgb(d / "lamp.exr", 16, 16, lambda x, y: (1.0 + (x % 4 == 0), 1.0, 0.6 + 0.4 * (y / 15)))
    exr_rgb(
        d / "sky.exr",
        64,
        32,
        lambda x, y: (
            0.4 + 0.8 * (1 - y / 31) + (30.0 if (x - 20) ** 2 + (y - 8) ** 2 < 4 else 0),
            0.5 + 0.9 * (1 - y / 31) + (28.0 if (x - 20) ** 2 + (y - 8) ** 2 < 4 else 0),
            0.8 + 1.2 * (1 - y / 31) + (24.0 if (x - 20) ** 2 + (y - 8) ** 2 < 4 else 0),
        ),
    )


ROOM = """  <bsdf type="twosided" id="wall"><bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.58, 0.55"/></bsdf></bsdf>
  <bsdf type="twosided" id="floor"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="planks.png"/></texture></bsdf></bsdf>
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform><ref id="floor"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="90"/><translate y="3"/></transform><ref id="wall"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="2" y="1.5"/><translate y="1.5" z="-2"/></transform><ref id="wall"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="2" y="1.5"/><rotate y="1" angle="90"/><translate x="-2" y="1.5"/></transform><ref id="wall"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="2" y="1.5"/><rotate y="1" angle="-90"/><translate x="2" y="1.5"/></transform><ref id="wall"/></shape>
"""

SENSOR = """  <sensor type="perspective">
    <float name="fov" value="{fov}"/><string name="fov_axis" value="y"/>
    <transform name="to_world"><lookat origin="{origin}" target="{target}" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/></film>
  </sensor>
"""


def sphere(at, radius, bsdf):
    x, y, z = at
    return (
        f'  <shape type="obj"><string name="filename" value="sphere.obj"/><boolean name="face_normals" value="true"/>'
        f'<transform name="to_world"><scale value="{radius}"/><translate x="{x}" y="{y}" z="{z}"/></transform>{bsdf}</shape>\n'
    )


def materials_scene(d, w, h):
    """Every BSDF luxest imports, in a lit room: spheres of conductor (smooth Au, GGX Cu,
    Beckmann Al), plastic, rough plastic (textured, nonlinear), dielectric, rough dielectric, a
    blend; a thin-dielectric pane and a one-sided textured panel; a textured area lamp and a
    point light. (The cut-out is a scene of its own: Mitsuba's `path` mishandles masks and its
    `volpath` passes point light through thin panes, which luxest's and `path`'s shadow rays
    do not.)"""
    b = [
        '<bsdf type="conductor"><string name="material" value="Au"/></bsdf>',
        '<bsdf type="roughconductor"><string name="material" value="Cu"/><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/></bsdf>',
        '<bsdf type="roughconductor"><string name="material" value="Al"/><string name="distribution" value="beckmann"/><float name="alpha" value="0.35"/></bsdf>',
        '<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.1, 0.3, 0.6"/></bsdf>',
        '<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.15"/><boolean name="nonlinear" value="true"/><texture type="bitmap" name="diffuse_reflectance"><string name="filename" value="checker.png"/></texture></bsdf>',
        '<bsdf type="dielectric"><float name="int_ior" value="1.5"/></bsdf>',
        '<bsdf type="roughdielectric"><string name="distribution" value="beckmann"/><float name="alpha" value="0.1"/><float name="int_ior" value="1.33"/></bsdf>',
        # A blend of non-delta models: Mitsuba's blendbsdf weighs a delta lobe's sample with the
        # other model's density as if the delta's "pdf 1" were one (its sample() mixes them), so
        # a blend with a smooth conductor comes out darker there than the exact value luxest's
        # test of a mirror-diffuse blend in a furnace checks.
        '<bsdf type="blendbsdf"><float name="weight" value="0.3"/><bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.2, 0.2"/></bsdf><bsdf type="roughconductor"><string name="material" value="Ag"/><float name="alpha" value="0.1"/></bsdf></bsdf>',
    ]
    body = ROOM
    for i, bsdf in enumerate(b):
        body += sphere((-1.4 + 0.8 * (i % 4), 0.35 + 0.9 * (i // 4), -0.9 + 0.5 * (i // 4)), 0.3, bsdf)
    body += """  <shape type="rectangle"><transform name="to_world"><scale x="0.4" y="0.5"/><rotate y="1" angle="25"/><translate x="-1.2" y="1.0" z="0.6"/></transform><bsdf type="thindielectric"><float name="int_ior" value="1.5"/></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="0.4" y="0.3"/><rotate y="1" angle="-30"/><translate x="1.3" y="1.6" z="0.2"/></transform><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="checker.png"/><string name="filter_type" value="nearest"/></texture></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="0.5" y="0.3"/><rotate x="1" angle="90"/><translate y="2.99" z="-0.3"/></transform><bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf><emitter type="area"><texture type="bitmap" name="radiance"><string name="filename" value="lamp.exr"/></texture></emitter></shape>
  <emitter type="point"><point name="position" value="1.2, 2.4, 1.0"/><rgb name="intensity" value="3, 2.8, 2.5"/></emitter>
"""
    write_scene(d / "materials.xml", body, dict(fov=55, origin="0, 1.5, 3.6", target="0, 1.0, 0", w=w, h=h))


def normals_scene(d, w, h):
    """Shading normals and normal maps: spheres whose OBJ carries vertex normals (smooth gold,
    rough plastic, diffuse; a one-sided rough conductor), a normal-mapped rough-plastic sphere,
    a normal-mapped diffuse panel and a normal-mapped floor (Mitsuba `normalmap`, raw bitmap,
    outside `twosided`), lit by the textured lamp and a point light."""
    smooth = [
        '<bsdf type="conductor"><string name="material" value="Au"/></bsdf>',
        '<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.1"/><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.7"/></bsdf>',
        '<bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.6, 0.5"/></bsdf>',
        '<bsdf type="roughconductor"><string name="material" value="Cu"/><string name="distribution" value="ggx"/><float name="alpha" value="0.15"/></bsdf>',
    ]
    bumps = '<texture type="bitmap" name="normalmap"><string name="filename" value="bumps.png"/><boolean name="raw" value="true"/></texture>'
    body = ROOM.replace(
        '<ref id="floor"/></shape>',
        f'<bsdf type="normalmap">{bumps}<ref id="floor"/></bsdf></shape>',
        1,
    )
    for i, bsdf in enumerate(smooth):
        wrapped = bsdf if i == 3 else f'<bsdf type="twosided">{bsdf}</bsdf>'
        x, y, z = -1.2 + 0.8 * i, 0.4, -0.6
        body += (
            '  <shape type="obj"><string name="filename" value="smooth.obj"/>'
            f'<transform name="to_world"><scale value="0.35"/><translate x="{x}" y="{y}" z="{z}"/></transform>{wrapped}</shape>\n'
        )
    mapped = (
        f'<bsdf type="normalmap">{bumps}<bsdf type="twosided"><bsdf type="roughplastic"><string name="distribution" value="ggx"/>'
        '<float name="alpha" value="0.2"/><rgb name="diffuse_reflectance" value="0.6, 0.3, 0.2"/></bsdf></bsdf></bsdf>'
    )
    body += (
        '  <shape type="obj"><string name="filename" value="smooth.obj"/>'
        f'<transform name="to_world"><scale value="0.4"/><translate x="0" y="1.3" z="-1.2"/></transform>{mapped}</shape>\n'
    )
    body += f"""  <shape type="rectangle"><transform name="to_world"><scale x="0.5" y="0.4"/><rotate y="1" angle="-25"/><translate x="1.2" y="1.5" z="-0.5"/></transform><bsdf type="normalmap">{bumps}<bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.8, 0.8"/></bsdf></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="0.5" y="0.3"/><rotate x="1" angle="90"/><translate y="2.99" z="-0.3"/></transform><bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf><emitter type="area"><texture type="bitmap" name="radiance"><string name="filename" value="lamp.exr"/></texture></emitter></shape>
  <emitter type="point"><point name="position" value="-1.2, 2.4, 1.0"/><rgb name="intensity" value="3, 2.8, 2.5"/></emitter>
"""
    write_scene(d / "normals.xml", body, dict(fov=55, origin="0, 1.5, 3.6", target="0, 1.0, 0", w=w, h=h))


def cutout_scene(d, w, h):
    """A cut-out leaf (Mitsuba `mask` of an RGBA bitmap, which Mitsuba reads by its colour's
    luminance) before the textured lamp, a one-sided panel and a sphere, lit also by a point
    light. Mitsuba renders it with `volpath` (see `integrator_of`)."""
    body = ROOM + sphere(
        (0.6, 0.5, -0.4), 0.4, '<bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf>'
    )
    body += """  <shape type="rectangle"><transform name="to_world"><scale x="0.35" y="0.35"/><rotate y="1" angle="15"/><translate x="0.2" y="1.9" z="0.3"/></transform><bsdf type="mask"><texture type="bitmap" name="opacity"><string name="filename" value="leaf.png"/><boolean name="raw" value="true"/></texture><bsdf type="twosided"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="leaf.png"/></texture></bsdf></bsdf></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="0.4" y="0.3"/><rotate y="1" angle="-30"/><translate x="1.3" y="1.6" z="0.2"/></transform><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="checker.png"/><string name="filter_type" value="nearest"/></texture></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="0.5" y="0.3"/><rotate x="1" angle="90"/><translate y="2.99" z="-0.3"/></transform><bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf><emitter type="area"><texture type="bitmap" name="radiance"><string name="filename" value="lamp.exr"/></texture></emitter></shape>
  <emitter type="point"><point name="position" value="1.2, 2.4, 1.0"/><rgb name="intensity" value="3, 2.8, 2.5"/></emitter>
"""
    write_scene(d / "cutout.xml", body, dict(fov=55, origin="0, 1.5, 3.6", target="0, 1.0, 0", w=w, h=h))


def emitters_scene(d, w, h):
    """Every emitter luxest imports: a room whose front wall has a window, lit by an
    environment map through it, plus a spot, a point light and, in a second scene, a constant
    environment seen through the same window."""
    window = """  <shape type="rectangle"><transform name="to_world"><scale x="2" y="0.5"/><translate y="0.5" z="2"/></transform><ref id="wall"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="2" y="0.5"/><translate y="2.5" z="2"/></transform><ref id="wall"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="0.5" y="0.5"/><translate x="-1.5" y="1.5" z="2"/></transform><ref id="wall"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="0.5" y="0.5"/><translate x="1.5" y="1.5" z="2"/></transform><ref id="wall"/></shape>
"""
    base = (
        ROOM
        + window
        + sphere(
            (0.3, 0.5, -0.6),
            0.45,
            '<bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.7, 0.6, 0.3"/></bsdf>',
        )
    )
    spot = """  <emitter type="spot"><transform name="to_world"><lookat origin="-1.5, 2.8, -1.5" target="0, 0, 0" up="0, 1, 0"/></transform><float name="cutoff_angle" value="25"/><float name="beam_width" value="15"/><rgb name="intensity" value="30, 28, 25"/></emitter>
  <emitter type="point"><point name="position" value="1.5, 2.5, -1.5"/><rgb name="intensity" value="2, 2, 2"/></emitter>
"""
    sensor = dict(fov=60, origin="0, 1.4, -1.9", target="0, 1.2, 2", w=w, h=h)
    env = '  <emitter type="envmap"><string name="filename" value="sky.exr"/><float name="scale" value="2"/><transform name="to_world"><rotate y="1" angle="30"/></transform></emitter>\n'
    write_scene(d / "daylight.xml", base + spot + env, sensor)
    const = '  <emitter type="constant"><rgb name="radiance" value="1.5, 1.6, 1.9"/></emitter>\n'
    write_scene(d / "overcast.xml", base + const, sensor)


def write_scene(path, body, sensor):
    path.write_text('<scene version="3.0.0">\n' + SENSOR.format(**sensor) + body + "</scene>\n")


def write_scenes(d, w, h):
    d.mkdir(parents=True, exist_ok=True)
    textures(d)
    icosphere_obj(d / "sphere.obj")
    icosphere_obj(d / "smooth.obj", normals=True)
    materials_scene(d, w, h)
    normals_scene(d, w, h)
    cutout_scene(d, w, h)
    emitters_scene(d, w, h)
    return {name: d / f"{name}.xml" for name in ("materials", "normals", "cutout", "daylight", "overcast")}


# ---- rendering and comparison --------------------------------------------------------------


def luxest(bins, xml, work, spp):
    """Imports and path-traces the scene: (Y image, its per-pixel standard error, CPU s,
    triangles)."""
    lxs = work / "scene.lxs"
    compile_cpu, _ = child_cpu([bins / "scene-compile", xml, "-o", lxs, "-q"])
    prefix = work / "luxest"
    cpu, _ = child_cpu([bins / "trace", lxs, "--spp", spp, "--seed", LUXEST_SEED, "--stderr", "-o", prefix, "-q"])
    name = prefix.name
    y = luminance(read_exr(work / image_name(name, "hdr", spp)))
    se = read_exr(work / image_name(name, "se", spp))[..., 0]
    # The compiled scene's RON header states the triangle count.
    tri = re.search(rb"triangles: (\d+)", lxs.read_bytes()[: 1 << 20])
    return y, se, compile_cpu + cpu, int(tri.group(1)) if tri else None


def integrator_of(xml_text):
    """Mitsuba's `path` for a scene, `volpath` where it has a `mask`: `path` treats a mask's
    transparency as a delta lobe without a matching light-sampling strategy and comes out
    darker (1.5 % on a half-opaque leaf before a lamp, 19 standard errors; `volpath` agrees
    with luxest there within 1), as Mitsuba's documentation of `mask` warns."""
    return "volpath" if '<bsdf type="mask"' in xml_text else "path"


def flattened(path, depth=0):
    """The text of a Mitsuba scene file with its `<include>`s inlined (their `<scene>` roots
    dropped) and every `<path>` made absolute, so that the film can be edited wherever it is."""
    path = Path(path).resolve()
    text = path.read_text()
    text = re.sub(
        r'<path\s+value="([^"]*)"\s*/>',
        lambda m: f'<path value="{(path.parent / m.group(1)).resolve()}"/>',
        text,
    )

    def inline(m):
        if depth > 15:
            sys.exit(f"error: {path}: includes nested more than 15 deep")
        inner = flattened(path.parent / m.group(1), depth + 1)
        inner = re.sub(r"<\?xml[^>]*\?>", "", inner)
        return re.sub(r"^\s*<scene[^>]*>|</scene>\s*$", "", inner.strip())

    return re.sub(r'<include\s+filename="([^"]*)"\s*/>', inline, text)


def resized(xml, size, work):
    """A copy of the public scene `xml` for both renderers, in `work`: includes inlined, the
    film set to `size` ("WxH"), and the scene's directory added to the file search (`<path>`),
    so luxest and Mitsuba read the same film — a field of view given along one axis
    (Mitsuba's `fov_axis`) then spans the same image for both."""
    text = flattened(xml)
    w, h = size.split("x")
    for name, v in (("width", w), ("height", h)):
        text, n = re.subn(
            rf'(<film type="hdrfilm"[^>]*>.*?<integer name="{name}" value=")[^"]*(")',
            rf"\g<1>{v}\g<2>",
            text,
            count=1,
            flags=re.S,
        )
        if n == 0:
            text = re.sub(r'(<film type="hdrfilm"[^>]*>)', rf'\1<integer name="{name}" value="{v}"/>', text, count=1)
    text = re.sub(
        r"(<scene\b[^>]*>)", lambda m: f'{m.group(1)}<path value="{Path(xml).resolve().parent}"/>', text, count=1
    )
    out = work / "scene.xml"
    write_text(out, text)
    return out


def film_size(text):
    """The (width, height) of a flattened scene's film."""
    film = re.search(r'<film type="hdrfilm"[^>]*>(.*?)</film>', text, re.S)
    size = {k: int(v) for k, v in re.findall(r'<integer name="(width|height)" value="(\d+)"\s*/>', film.group(1))}
    return size.get("width", 768), size.get("height", 576)


def mitsuba(xml, spp, variant):
    """Mitsuba renders of the same file (includes inlined; box filter; `path` with unbounded
    depth, or `volpath`), REPS runs with distinct seeds: (their mean Y, the per-run Y images,
    CPU s, the integrator)."""
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(variant)
    text = flattened(xml)
    # luxest integrates each pixel's area: Mitsuba's film gets a box filter.
    text = re.sub(r"<rfilter[^>]*/>", "", text)
    text = re.sub(r'(<film type="hdrfilm"[^>]*>)', r'\1<rfilter type="box"/>', text)
    mi.file_resolver().prepend(str(Path(xml).resolve().parent))
    t = time.process_time()
    scene = mi.load_string(text)
    integrator = mi.load_dict({"type": integrator_of(text), "max_depth": -1, "rr_depth": 5})
    runs = []
    per = max(1, spp // REPS)
    for k in range(REPS):
        img = mi.render(scene, integrator=integrator, spp=per, seed=MITSUBA_SEED + k)
        dr.eval(img)
        runs.append(luminance(np.array(img, dtype=np.float64)[..., :3]))
    cpu = time.process_time() - t
    return np.mean(runs, axis=0), np.array(runs), cpu, integrator_of(text)


def blocks(a, n=BLOCKS):
    h, w = a.shape[-2] // n, a.shape[-1] // n
    return np.array(
        [[a[..., i * h : (i + 1) * h, j * w : (j + 1) * w].mean(axis=(-1, -2)) for j in range(n)] for i in range(n)]
    )


def compare(y_l, se_l, y_m, runs):
    """z of the whole-image mean and of each block: luxest's standard error from its pixels'
    (independent samples), Mitsuba's from the spread of its REPS runs."""
    hh, ww = y_l.shape
    cut = lambda a: a[..., : hh // BLOCKS * BLOCKS, : ww // BLOCKS * BLOCKS]  # noqa: E731
    y_l, se_l, runs = cut(y_l), cut(se_l), cut(runs)
    n = BLOCKS * BLOCKS
    px = (hh // BLOCKS) * (ww // BLOCKS)
    bl = blocks(y_l)
    bl_se = np.sqrt(blocks(se_l**2) / px)
    br = blocks(runs)  # (BLOCKS, BLOCKS, REPS)
    bm = br.mean(axis=-1)
    bm_se = br.std(axis=-1, ddof=1) / math.sqrt(REPS)
    # Both images are f32: where neither renderer has noise (the sky seen directly) their
    # values agree to f32 rounding, not exactly.
    z_blocks = (bl - bm) / np.sqrt(bl_se**2 + bm_se**2 + (F32_ROUNDING * bm) ** 2 + 1e-300)
    whole_l, whole_l_se = y_l.mean(), math.sqrt((se_l**2).sum()) / se_l.size
    whole_runs = runs.mean(axis=(-1, -2))
    whole_m, whole_m_se = whole_runs.mean(), whole_runs.std(ddof=1) / math.sqrt(REPS)
    z = (whole_l - whole_m) / math.hypot(whole_l_se, whole_m_se)
    return dict(
        mean_l=whole_l,
        se_l=whole_l_se,
        mean_m=whole_m,
        se_m=whole_m_se,
        z=z,
        max_z=float(np.abs(z_blocks).max()),
        over4=int((np.abs(z_blocks) > 4).sum()),
        blocks=n,
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bins", required=True, help="directory of luxest's binaries")
    ap.add_argument("--work-dir", required=True)
    ap.add_argument("--scene", action="append", default=[], help="NAME=PATH of a public Mitsuba 3 scene")
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--resolution", default="256x192", help="of the scenes this script writes")
    ap.add_argument(
        "--public-pixels",
        type=int,
        default=256 * 192,
        help="public scenes are rendered at about this many pixels, their film's aspect kept",
    )
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--only", help="comma-separated names of this script's scenes to run (others are skipped)")
    ap.add_argument("-o", "--out", required=True)
    a = ap.parse_args(argv)
    work, bins = Path(a.work_dir), Path(a.bins)
    w, h = (int(v) for v in a.resolution.split("x"))
    import mitsuba as mi

    mi.set_variant(a.variant)
    scenes = write_scenes(work / "scenes", w, h)
    if a.only is not None:
        scenes = {k: v for k, v in scenes.items() if k in a.only.split(",")}
    for s in a.scene:
        name, _, path = s.partition("=")
        scenes[name] = Path(path)
    rows, failures = [], []
    public = {name for name, _ in (s.partition("=")[::2] for s in a.scene)}
    for name, xml in scenes.items():
        d = work / name
        d.mkdir(parents=True, exist_ok=True)
        if name in public:
            fw, fh = film_size(flattened(xml))
            k = math.sqrt(a.public_pixels / (fw * fh))
            xml = resized(xml, f"{max(1, round(fw * k))}x{max(1, round(fh * k))}", d)
        y_l, se_l, cpu_l, tris = luxest(bins, xml, d, a.spp)
        y_m, runs, cpu_m, integrator = mitsuba(xml, a.spp, a.variant)
        c = compare(y_l, se_l, y_m, runs)
        rows.append((name, tris, cpu_l, cpu_m, c, integrator))
        if abs(c["z"]) > 3 or c["max_z"] > 4.5:
            failures.append(name)
        print(
            f"{name}: z {c['z']:+.2f}, max block |z| {c['max_z']:.2f}, luxest {cpu_l:.1f} CPU-s, Mitsuba {cpu_m:.1f} CPU-s",
            flush=True,
        )
    out = [
        "# Mitsuba 3 XML scenes: luxest `trace` against Mitsuba 3",
        "",
        f"Host: {host_summary()}. {a.spp} spp each (Mitsuba: {REPS} runs of {a.spp // REPS} spp, `{a.variant}`, "
        "box filter, `volpath` where a scene has a `mask`); whole-image mean Y with standard errors, z of their difference; 16 × 16 blocks: largest |z| and "
        "how many exceed 4. Written by `pipelines/bench_scenes.py` (`make bench-scenes`).",
        "",
        "| scene | triangles | luxest CPU-s | Mitsuba 3 CPU-s | Mitsuba integrator | luxest mean Y | Mitsuba 3 mean Y | z | max block \\|z\\| | blocks \\|z\\| > 4 |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, tris, cpu_l, cpu_m, c, integrator in rows:
        out.append(
            f"| {name} | {tris} | {cpu_l:.1f} | {cpu_m:.1f} | `{integrator}` | {c['mean_l']:.5g} ± {c['se_l']:.2g} | "
            f"{c['mean_m']:.5g} ± {c['se_m']:.2g} | {c['z']:+.2f} | {c['max_z']:.2f} | {c['over4']} of {c['blocks']} |"
        )
    out += ["", "Agreement within noise: " + ("every scene" if not failures else "NOT " + ", ".join(failures)), ""]
    write_text(Path(a.out), "\n".join(out))
    print("\n".join(out))
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
