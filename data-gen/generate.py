#!/usr/bin/env python3
"""Seeded generator of varied training scenes for the denoiser (standard library only).

Each scene is a room (floor, ceiling and four walls with their own reflectances) furnished with
primitives (boxes as tables, cabinets and blocks; spheres) and meshes (the torus and trefoil of
scenes/meshes), in Lambertian, glossy, plastic and metal and, in some scenes, mirror and glass
materials, lit by one to several emitters of varied size, flux and position: ceiling panels,
small very bright spheres (the firefly makers) and point sources, white or strongly coloured;
about a third of the reflectances are saturated colours. The camera stands somewhere in the room
looking at something, or, in a quarter of the rooms, outside a room open at the front (as the
Cornell box is seen), so that views include empty background. Everything follows from (seed,
index), so a scene regenerates byte for byte.

Three rooms in four are textured from the procedural library of data-gen/textures.py (written
once per dataset, DIR/textures/<name>.png, named from the scenes as ../textures/<name>.png):
wood, tile, marble and carpet floors, plastered, tiled, panelled or papered walls, textured
furniture boxes and meshes (colour textures multiplying the Lambertian, glossy and plastic
diffuse colours and the metals' specular colour, repeated at varied scales and offsets by
`uv_transform`), pictures and pages hung on the walls, cut-out plants and grilles (opacity), and
textured emitters (windows, patterned ceiling panels). The other rooms, and the spheres (which
have no texture coordinates), stay untextured.

A quarter of the rooms (SKY_SHARE, drawn from a generator of their own so that the rest of a room
is what it would be without) are daylit as well: an environment — the CIE overcast, intermediate
or clear sky (with or without the sun, 3000 to 20 000 lx diffuse horizontal illuminance) or a
constant one of 500 to 8000 cd/m² — shining through an opening cut in the right wall and, in
rooms open at the front, seen past the opening.

  generate.py --preset quick|full --side N --out DIR   write DIR/<split>/<name>.ron, N x N
                                                       images, and the library DIR/textures/
  generate.py ... --only scenes|textures               write only the scenes or only the library
  generate.py --preset quick --list                    print "<split>/<name>" per scene
  generate.py --list-textures                          print the library's file names
  ... --scenes N                                       N scenes instead of the preset's count

The preset selects the number of scenes (--scenes overrides it: pipelines/presets.mk
DATASET_COUNT); the image side comes from pipelines/presets.mk (DATASET_SIDE), which passes it.
Scene i does not depend on the count, so a dataset of more scenes contains the smaller one's.
The library depends on the seed only (TEXTURE_SIDE pixels square).

Splits: scene i goes to test if i % 6 == 5, to valid if i % 6 == 4, else to train.
"""

import argparse
import math
import os
import random
import sys
from pathlib import Path

import textures as library

# Scenes per preset (the image side is DATASET_SIDE in pipelines/presets.mk).
PRESETS = {
    "quick": 24,
    "full": 240,
}
MESHES = Path(__file__).resolve().parent.parent / "scenes" / "meshes"
# The texture library: its directory under --out, the side of its images. Scenes lie one level
# below --out (DIR/<split>/), so they name a texture ../textures/<name>.png.
TEXTURE_DIR = "textures"
TEXTURE_SIDE = 256
# Library textures by use, with the width in metres one image covers at scale 1 (a plank row is
# a quarter of wood-planks, a tile a quarter of tiles).
FLOORS = {"wood-planks": 0.9, "tiles": 1.2, "marble": 1.6, "fabric": 0.35}
WALLS = {"plaster": 2.0, "tiles": 0.9, "fabric": 0.5, "wood-planks": 1.0, "marble": 1.8, "paper-text": 0.8}
FURNITURE = {"wood-planks": 0.8, "marble": 0.9, "fabric": 0.3, "tiles": 0.6, "plaster": 1.2}
# Materials of the furniture and meshes, with their weights: Lambertian, glossy (Glossy), plastic
# (Plastic: a diffuse base under a smooth or rough coating), metal (Conductor, smooth or rough),
# mirror and glass.
KINDS = {"lambert": 0.5, "glossy": 0.2, "plastic": 0.12, "metal": 0.08, "mirror": 0.05, "glass": 0.05}
# Conductors' complex index of refraction (eta, k) at the R, G and B wavelengths of Mitsuba 3's
# RGB mode for its spectral tables (the gold is the one of crates/render/tests/data/mitsuba_bsdf.ron).
METALS = {
    "gold": ((0.143, 0.374, 1.442), (3.983, 2.385, 1.603)),
    "copper": ((0.200, 0.924, 1.102), (3.912, 2.452, 2.142)),
    "aluminium": ((1.657, 0.880, 0.521), (9.224, 6.270, 4.837)),
    "silver": ((0.155, 0.117, 0.138), (4.828, 3.122, 2.147)),
    "chromium": ((4.368, 2.910, 1.654), (5.205, 4.231, 3.755)),
}
# The share of rooms lit by daylight too: a sky through an opening in the right wall.
SKY_SHARE = 0.25
# Length along the meshes' u (the ring, the knot) over the length around their tube (v).
MESH_ASPECT = {"torus.obj": 3, "trefoil.glb": 12}
PICTURES = ("photo-landscape", "photo-still-life", "paper-text")
# Images whose own colour is their point: their material's colour only tints them a little.
COLOURED = {"wood-planks", "photo-landscape", "photo-still-life", "leaves", "paper-text"}


def split_of(i):
    return "test" if i % 6 == 5 else "valid" if i % 6 == 4 else "train"


def names(preset, count=None):
    n = PRESETS[preset] if count is None else count
    return [(split_of(i), f"gen{i:04d}") for i in range(n)]


def f(x):
    return f"{x:.4f}"


def v3(a, b, c):
    return f"({f(a)}, {f(b)}, {f(c)})"


def color(rng, lo=0.05, hi=0.85):
    base = rng.uniform(lo, hi)
    if rng.random() < 0.35:
        # Saturated, like the Cornell box's red (0.63, 0.065, 0.05) and green walls: one
        # dominant channel, the others 5-60 % of it.
        factors = [1.0, rng.uniform(0.05, 0.6), rng.uniform(0.05, 0.6)]
        rng.shuffle(factors)
        return v3(*[min(hi, max(0.02, max(base, 0.3) * k)) for k in factors])
    tint = [min(hi, max(lo, base * rng.uniform(0.6, 1.4))) for _ in range(3)]
    return v3(*tint)


def light_tint(rng):
    """Mostly warm or neutral white; 40 % strongly coloured (the Cornell light is
    (1, 0.7, 0.24) in relative RGB)."""
    if rng.random() < 0.4:
        t = [1.0, rng.uniform(0.4, 1.0), rng.uniform(0.1, 1.0)]
        rng.shuffle(t)
        return tuple(t)
    return (1.0, rng.uniform(0.75, 1.0), rng.uniform(0.5, 1.0))


def luminance(r, g, b):
    # Rec. 709 luminance of linear RGB (docs/scene-format.md, Units).
    return 0.2126 * r + 0.7152 * g + 0.0722 * b


def scene(preset, index, seed, side, scene_dir=None):
    rng = random.Random(seed * 1_000_003 + index)
    w, h, d = rng.uniform(3.0, 7.0), rng.uniform(2.4, 3.6), rng.uniform(3.0, 7.0)
    materials, objects, lights = {}, [], []
    textures, surfaces = {}, {}
    textured = rng.random() < 0.75

    def texture(lib, su=1.0, sv=1.0, fixed=False):
        """A `textures` entry of library image `lib` repeated su x sv times over the shape's
        texture coordinates, from a random offset, a quarter of them turned by 90 degrees
        (`fixed`: the image once, upright, clamped at its edges); its name."""
        name = f"t{len(textures)}"
        path = f"../{TEXTURE_DIR}/{lib}.png"
        if fixed:
            textures[name] = f'(path: "{path}", wrap: Clamp)'
            return name
        ou, ov = rng.random(), rng.random()
        if rng.random() < 0.25:
            m = f"((0.0, {f(su)}, {f(ou)}), ({f(sv)}, 0.0, {f(ov)}))"
        else:
            m = f"(({f(su)}, 0.0, {f(ou)}), (0.0, {f(sv)}, {f(ov)}))"
        textures[name] = f'(path: "{path}", uv_transform: {m})'
        return name

    def material(kind=None, tex=None, cut_out=False):
        """A new material of `kind` (drawn when None); `tex`: (library image, su, sv, fixed)
        makes a Lambertian, glossy, plastic or metal one textured, its main colour a tint of the
        image, and with `cut_out` its alpha the opacity (opaque where it reaches 0.5)."""
        name = f"m{len(materials)}"
        kind = kind or rng.choices(list(KINDS), list(KINDS.values()))[0]
        tex = tex if kind in ("lambert", "glossy", "plastic", "metal") else None
        if tex is not None:
            lib = tex[0]
            tint = v3(*[rng.uniform(0.8, 1.0) for _ in range(3)]) if lib in COLOURED else color(rng, 0.35, 0.95)
            t = texture(*tex)
            opacity = f', opacity: Some((texture: Some("{t}"), cutoff: Some(0.5)))' if cut_out else ""
            surfaces[name] = f'(color: Some("{t}"){opacity})'
        if kind == "lambert":
            materials[name] = f"Lambertian(reflectance: {tint if tex else color(rng)})"
        elif kind == "glossy":
            dif = rng.uniform(0.05, 0.5) if tex is None else rng.uniform(0.4, 0.75)
            spec = rng.uniform(0.1, 0.9 - dif) if tex is None else rng.uniform(0.04, 0.95 - dif)
            diffuse = (
                v3(dif, dif * rng.uniform(0.7, 1.0), dif * rng.uniform(0.5, 1.0)) if tex is None else v3(dif, dif, dif)
            )
            materials[name] = (
                f"Glossy(diffuse: {diffuse}, specular: {v3(spec, spec, spec)}, roughness: {f(rng.uniform(0.08, 0.7))})"
            )
        elif kind == "plastic":
            nonlinear = ", nonlinear: true" if rng.random() < 0.2 else ""
            rough = f", roughness: Some({microfacet()})" if rng.random() < 0.6 else ""
            materials[name] = (
                f"Plastic(diffuse_reflectance: {tint if tex else color(rng)}, ior: {f(rng.uniform(1.4, 1.6))}"
                f"{nonlinear}{rough})"
            )
        elif kind == "metal":
            eta, k = METALS[rng.choice(sorted(METALS))]
            r = rng.uniform(0.85, 1.0)
            rough = f", roughness: Some({microfacet()})" if rng.random() < 0.8 else ""
            materials[name] = (
                f"Conductor(eta: {v3(*eta)}, k: {v3(*k)}, specular_reflectance: {tint if tex else v3(r, r, r)}{rough})"
            )
        elif kind == "mirror":
            r = rng.uniform(0.7, 0.95)
            materials[name] = f"Mirror(reflectance: {v3(r, r, r)})"
        else:
            materials[name] = f"Dielectric(ior: {f(rng.uniform(1.33, 1.7))})"
        return name

    def microfacet():
        return f"(distribution: {rng.choice(['Ggx', 'Beckmann'])}, alpha: {f(rng.uniform(0.05, 0.5))})"

    def maybe(choices, width, height, p):
        """With probability p (in a textured room), a texture of `choices` (library image ->
        metres per image) repeated over a width x height surface; else None."""
        if not (textured and rng.random() < p):
            return None
        lib = rng.choice(sorted(choices))
        k = rng.uniform(0.6, 1.6) / choices[lib]
        return (lib, max(0.25, width * k), max(0.25, height * k), False)

    # The room: six quads, faces towards the inside; (name, corner, u, v, extent along u, along v).
    walls = [
        ("floor", v3(0, 0, d), v3(w, 0, 0), v3(0, 0, -d), w, d),
        ("ceiling", v3(0, h, 0), v3(w, 0, 0), v3(0, 0, d), w, d),
        ("back", v3(0, 0, d), v3(0, h, 0), v3(w, 0, 0), h, w),
        ("front", v3(0, 0, 0), v3(w, 0, 0), v3(0, h, 0), w, h),
        ("left", v3(0, 0, 0), v3(0, h, 0), v3(0, 0, d), h, d),
        ("right", v3(w, 0, 0), v3(0, 0, d), v3(0, h, 0), d, h),
    ]
    # A quarter of the rooms are open at the front and seen from outside, as the Cornell box is:
    # the views then include empty background (no hit: zero radiance, albedo and normal).
    open_front = rng.random() < 0.25
    # One wall covering for the four walls of a textured room (each wall its own scale).
    wall_lib = rng.choice(sorted(WALLS)) if textured and rng.random() < 0.6 else None
    # Daylight in some rooms (from an rng of its own, so the other draws are those of a room
    # without it): an environment (the CIE overcast, intermediate or clear sky, or a constant
    # one) seen through an opening cut in the right wall, and past the open front of a room seen
    # from outside.
    sky_rng = random.Random(f"sky-{seed}-{index}")
    sky = sky_rng.random() < SKY_SHARE
    hole = None
    if sky:
        hw, hh = sky_rng.uniform(0.6, min(2.0, d - 0.6)), sky_rng.uniform(0.6, min(1.6, h - 1.0))
        hole = (sky_rng.uniform(0.8, h - hh - 0.2), sky_rng.uniform(0.3, d - hw - 0.3), hh, hw)
    for name, corner, u, v, su, sv in walls:
        if open_front and name == "front":
            continue
        if hole is not None and name == "right":
            # The right wall (x = w, u along z, v along y) around the opening: below, above,
            # and either side.
            y0, z0, hh, hw = hole
            m = material("lambert")
            pieces = [(0, 0, d, y0), (0, y0 + hh, d, h - y0 - hh), (0, y0, z0, hh), (z0 + hw, y0, d - z0 - hw, hh)]
            for j, (z, y, lz, ly) in enumerate(pieces):
                objects.append(
                    f'(name: "right{j}", shape: Quad(corner: {v3(w, y, z)}, u: {v3(0, 0, lz)}, v: {v3(0, ly, 0)}), material: "{m}")'
                )
            continue
        if name == "floor":
            tex = maybe(FLOORS, su, sv, 0.85)
        elif name == "ceiling":
            tex = maybe({"plaster": 2.0}, su, sv, 0.3)
        elif wall_lib is not None:
            k = rng.uniform(0.8, 1.2) / WALLS[wall_lib]
            tex = (wall_lib, su * k, sv * k, False)
        else:
            tex = None
        objects.append(
            f'(name: "{name}", shape: Quad(corner: {corner}, u: {u}, v: {v}), material: "{material("lambert", tex)}")'
        )

    # Pictures and pages on the back and side walls, 1 cm in front of them, upright as seen from
    # the room: u = up x n (n the wall's inward normal), v = up.
    if textured:
        for k in range(rng.choice([0, 1, 1, 2, 3])):
            wall = rng.choice(["back", "left", "right"])
            size = rng.uniform(0.3, 1.1)
            length = w if wall == "back" else d
            a = rng.uniform(0.2, max(0.2, length - size - 0.2))
            y = rng.uniform(0.9, max(0.9, h - size - 0.3))
            if wall == "back":
                corner, u = v3(a + size, y, d - 0.01), v3(-size, 0, 0)
            elif wall == "left":
                corner, u = v3(0.01, y, a + size), v3(0, 0, -size)
            else:
                corner, u = v3(w - 0.01, y, a), v3(0, 0, size)
            m = material("lambert", (rng.choice(PICTURES), 1.0, 1.0, True))
            objects.append(
                f'(name: "picture{k}", shape: Quad(corner: {corner}, u: {u}, v: {v3(0, size, 0)}), material: "{m}")'
            )

    # Furniture.
    targets = []
    for k in range(rng.randint(2, 7)):
        x, z = rng.uniform(0.6, w - 0.6), rng.uniform(0.6, d - 0.6)
        targets.append((x, z))
        kind = rng.choice(["table", "block", "sphere", "mesh", "cabinet"])
        if kind == "table":
            tw, td, th = rng.uniform(0.6, 1.6), rng.uniform(0.5, 1.0), rng.uniform(0.6, 0.9)
            m = material(tex=maybe(FURNITURE, tw, td, 0.7))
            objects.append(
                f'(name: "table{k}", shape: Box(size: {v3(tw, 0.05, td)}), transform: (translate: {v3(x, th, z)}), material: "{m}")'
            )
            for dx in (-1, 1):
                for dz in (-1, 1):
                    objects.append(
                        f'(shape: Box(size: {v3(0.05, th, 0.05)}), transform: (translate: {v3(x + dx * (tw / 2 - 0.05), th / 2, z + dz * (td / 2 - 0.05))}), material: "{m}")'
                    )
        elif kind in ("block", "cabinet"):
            sx, sy, sz = (
                rng.uniform(0.2, 1.2),
                rng.uniform(0.2, 1.8 if kind == "cabinet" else 0.8),
                rng.uniform(0.2, 1.0),
            )
            m = material(tex=maybe(FURNITURE, max(sx, sz), sy, 0.7))
            objects.append(
                f'(name: "{kind}{k}", shape: Box(size: {v3(sx, sy, sz)}), transform: (rotate_deg: {v3(0, rng.uniform(0, 90), 0)}, translate: {v3(x, float(f(sy)) / 2, z)}), material: "{m}")'
            )
        elif kind == "sphere":
            r = rng.uniform(0.1, 0.5)
            # Spheres have no texture coordinates: untextured.
            objects.append(
                f'(name: "sphere{k}", shape: Sphere(radius: {f(r)}, subdivisions: 3), transform: (translate: {v3(x, r, z)}), material: "{material()}")'
            )
        else:
            mesh = rng.choice(["torus.obj", "trefoil.glb"])
            # Relative to the scene file, so the generated text does not depend on the checkout.
            rel = os.path.relpath(MESHES / mesh, scene_dir) if scene_dir else str(MESHES / mesh)
            shape = f'Obj(path: "{rel}")' if mesh.endswith(".obj") else f'Gltf(path: "{rel}")'
            tex = maybe(FURNITURE, 1.0, 1.0, 0.7)
            if tex is not None:
                # The meshes' texture coordinates run once along the ring (the knot) and once
                # around the tube, which is a third (a twelfth) as long: repeats in that ratio.
                reps = rng.randint(1, 3)
                tex = (tex[0], float(MESH_ASPECT[mesh] * reps), float(reps), False)
            m = material(tex=tex)
            sc = rng.uniform(0.6, 1.5)
            objects.append(
                f'(name: "mesh{k}", shape: {shape}, transform: (scale: {v3(sc, sc, sc)}, rotate_deg: {v3(rng.uniform(0, 90), rng.uniform(0, 360), 0)}, translate: {v3(x, rng.uniform(0.3, 1.2), z)}), material: "{m}")'
            )

    # Cut-outs: a plant (two crossed quads of leaves) and a grille screen, in some textured rooms;
    # the image's alpha is the opacity, opaque where it reaches 0.5.
    if textured and rng.random() < 0.35:
        x, z, size = rng.uniform(0.8, w - 0.8), rng.uniform(0.8, d - 0.8), rng.uniform(0.6, 1.3)
        m = material("lambert", ("leaves", 1.0, 1.0, False), cut_out=True)
        for k, (u, corner) in enumerate(
            [(v3(size, 0, 0), v3(x - size / 2, 0, z)), (v3(0, 0, size), v3(x, 0, z - size / 2))]
        ):
            objects.append(
                f'(name: "plant{k}", shape: Quad(corner: {corner}, u: {u}, v: {v3(0, size, 0)}), material: "{m}")'
            )
    if textured and rng.random() < 0.2:
        gw, gh = rng.uniform(0.8, 2.0), rng.uniform(1.2, h - 0.3)
        x, z = rng.uniform(0.3, max(0.3, w - gw - 0.3)), rng.uniform(1.0, d - 0.5)
        # Holes of 6 to 15 cm: the image has 8 across.
        cell = rng.uniform(0.06, 0.15)
        m = material("lambert", ("grille", gw / (8 * cell), gh / (8 * cell), False), cut_out=True)
        objects.append(
            f'(name: "grille", shape: Quad(corner: {v3(x, 0.01, z)}, u: {v3(gw, 0, 0)}, v: {v3(0, gh, 0)}), material: "{m}")'
        )

    # Emitters: at least one, of several kinds.
    emitter_material = material("lambert")
    for k in range(rng.randint(1, 4)):
        kind = rng.choices(["panel", "bulb", "point"], [0.5, 0.3, 0.2])[0]
        tint = light_tint(rng)
        if kind == "panel":
            pw, pd = rng.uniform(0.2, 1.5), rng.uniform(0.2, 1.5)
            px, pz = rng.uniform(0.2, w - pw - 0.2), rng.uniform(0.2, d - pd - 0.2)
            lumens = rng.uniform(500, 6000)
            if textured and rng.random() < 0.25:
                # A patterned diffuser: luminance scale x texel, the scale set for about the
                # requested flux at a mean texel luminance of 0.4.
                y = lumens / (math.pi * pw * pd * 0.4) / luminance(*tint)
                lib = rng.choice(["fabric", "tiles", "grille", "plaster"])
                emission = f'Texture(texture: "{texture(lib, rng.uniform(1, 3), rng.uniform(1, 3))}", scale: {v3(*[c * y for c in tint])})'
            else:
                emission = f"Flux(lumens: {f(lumens)}, color: {v3(*tint)})"
            objects.append(
                f'(name: "panel{k}", shape: Quad(corner: {v3(px, h - 0.01, pz)}, u: {v3(pw, 0, 0)}, v: {v3(0, 0, pd)}), '
                f'material: "{emitter_material}", emission: {emission})'
            )
        elif kind == "bulb":
            # Small and bright: the caustic and firefly makers.
            r = rng.uniform(0.02, 0.08)
            objects.append(
                f'(name: "bulb{k}", shape: Sphere(radius: {f(r)}, subdivisions: 2), transform: (translate: {v3(rng.uniform(0.3, w - 0.3), rng.uniform(0.5, h - 0.3), rng.uniform(0.3, d - 0.3))}), '
                f'material: "{emitter_material}", emission: Flux(lumens: {f(rng.uniform(200, 3000))}, color: {v3(*tint)}))'
            )
        else:
            lights.append(
                f"(position: {v3(rng.uniform(0.3, w - 0.3), rng.uniform(0.5, h - 0.2), rng.uniform(0.3, d - 0.3))}, power: Flux({f(rng.uniform(300, 3000))}), color: {v3(*tint)})"
            )
    # A window in some textured rooms: a landscape photograph glowing on a side wall (the view
    # out), 5 mm in front of it, 300 to 3000 cd/m² at a texel of 1.
    if textured and rng.random() < 0.2:
        ww, wh = rng.uniform(0.6, min(1.6, d - 0.6)), rng.uniform(0.6, min(1.4, h - 1.2))
        a, y = rng.uniform(0.3, d - ww - 0.3), rng.uniform(0.9, h - wh - 0.2)
        L = rng.uniform(300, 3000)
        objects.append(
            f'(name: "window", shape: Quad(corner: {v3(0.005, y, a + ww)}, u: {v3(0, 0, -ww)}, v: {v3(0, wh, 0)}), '
            f'material: "{emitter_material}", emission: Texture(texture: "{texture("photo-landscape", fixed=True)}", scale: {v3(L, L, L)}))'
        )

    # The camera looks at a piece of furniture from the front part of the room.
    tx, tz = rng.choice(targets)
    if open_front:
        # Far enough that the opening does not fill the view, looking into the room.
        cam = v3(rng.uniform(0.3 * w, 0.7 * w), rng.uniform(0.8, h - 0.3), -rng.uniform(2.0, 6.0))
        look = v3(rng.uniform(0.4 * w, 0.6 * w), rng.uniform(0.3 * h, 0.6 * h), d / 2)
    else:
        cam = v3(rng.uniform(0.3, w - 0.3), rng.uniform(0.8, h - 0.5), rng.uniform(0.2, min(0.8, tz - 0.3)))
        look = v3(tx, rng.uniform(0.2, 1.0), tz)
    environment = ""
    if sky:
        kind = sky_rng.choice(["Overcast", "Intermediate", "Clear", "Constant"])
        if kind == "Constant":
            lum = f(sky_rng.uniform(500, 8000))
            environment = f"    environment: Constant(({lum}, {lum}, {lum})),\n"
        else:
            alt, azi = f(sky_rng.uniform(10, 60)), f(sky_rng.uniform(-180, 180))
            sun = "true" if kind != "Overcast" and sky_rng.random() < 0.5 else "false"
            environment = (
                f"    environment: Sky((kind: {kind}, sun: {sun}, angles: Some((altitude: {alt}, azimuth: {azi})), "
                f"horizontal_illuminance: Some({f(sky_rng.uniform(3000, 20000))}), resolution: 128)),\n"
            )
    mats = ",\n        ".join(f'"{k}": {v}' for k, v in materials.items())
    objs = ",\n        ".join(objects)
    lts = ",\n        ".join(lights)
    tex = "".join(
        f"    {field}: {{\n" + "".join(f'        "{k}": {v},\n' for k, v in table.items()) + "    },\n"
        for field, table in (("textures", textures), ("surfaces", surfaces))
        if table
    )
    return f"""// Generated by data-gen/generate.py --preset {preset} (scene {index}, seed {seed}).
Scene(
    camera: Camera(position: {cam}, look_at: {look}, vfov_deg: {f(rng.uniform(45, 75))}, resolution: ({side}, {side})),
    materials: {{
        {mats},
    }},
{tex}{environment}    objects: [
        {objs},
    ],
    point_lights: [
        {lts}
    ],
)
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="quick", choices=sorted(PRESETS))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--side", type=int, help="image side in pixels (required with --out)")
    ap.add_argument("--out", type=Path)
    ap.add_argument(
        "--scenes",
        type=int,
        help="number of scenes (default: the preset's); scene i "
        "is the same whatever the count, so a larger count adds scenes to every split",
    )
    ap.add_argument(
        "--only",
        choices=["scenes", "textures"],
        help="write only the scenes or only the texture library (default: both; make writes each in a rule of its own)",
    )
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--list-textures", action="store_true", help="print the library's files, relative to --out")
    args = ap.parse_args()
    if args.list_textures:
        print(" ".join(f"{TEXTURE_DIR}/{name}.png" for name in library.NAMES))
        return
    if args.scenes is not None and not 6 <= args.scenes <= 100_000:
        ap.error(f"--scenes {args.scenes}: expected 6 to 100000 (at least one scene per split)")
    scenes = names(args.preset, args.scenes)
    if args.list:
        print(" ".join(f"{s}/{n}" for s, n in scenes))
        return
    if args.out is None:
        ap.error("--out is required unless --list")
    if args.only != "textures" and (args.side is None or not 16 <= args.side <= 8192):
        ap.error("--side: the image side in pixels, 16 to 8192, is required with --out")
    if args.only != "scenes":
        library.write_library(args.out / TEXTURE_DIR, TEXTURE_SIDE, args.seed)
        print(f"{len(library.NAMES)} textures in {args.out / TEXTURE_DIR}", file=sys.stderr)
    if args.only == "textures":
        return
    for i, (split, name) in enumerate(scenes):
        path = args.out / split / f"{name}.ron"
        path.parent.mkdir(parents=True, exist_ok=True)
        text = scene(args.preset, i, args.seed, args.side, path.parent.resolve())
        # Rewrite only what changed, so make rebuilds only what changed.
        if not path.exists() or path.read_text() != text:
            tmp = path.with_suffix(f".ron.{os.getpid()}.tmp")  # unique: make -j may run two generators
            tmp.write_text(text)
            tmp.replace(path)
    print(f"{len(scenes)} scenes in {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
