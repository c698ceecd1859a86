#!/usr/bin/env python3
"""Seeded generator of varied training scenes for the denoiser (standard library only).

Each scene is a room (floor, ceiling and four walls with their own reflectances) furnished with
primitives (boxes as tables, cabinets and blocks; spheres) and meshes (the torus and trefoil of
scenes/meshes), in Lambertian, glossy and, in some scenes, mirror and glass materials, lit by one
to several emitters of varied size, flux and position: ceiling panels, small very bright spheres
(the firefly makers) and point sources, white or strongly coloured; about a third of the
reflectances are saturated colours. The camera stands somewhere in the room looking at
something, or, in a quarter of the rooms, outside a room open at the front (as the Cornell box
is seen), so that views include empty background. Everything follows from (seed, index), so a scene regenerates byte for byte.

  generate.py --preset quick|full --side N --out DIR   write DIR/<split>/<name>.ron, N x N images
  generate.py --preset quick --list                    print "<split>/<name>" per scene
  ... --scenes N                                       N scenes instead of the preset's count

The preset selects the number of scenes (--scenes overrides it: pipelines/presets.mk
DATASET_COUNT); the image side comes from pipelines/presets.mk (DATASET_SIDE), which passes it.
Scene i does not depend on the count, so a dataset of more scenes contains the smaller one's.

Splits: scene i goes to test if i % 6 == 5, to valid if i % 6 == 4, else to train.
"""

import argparse
import os
import random
import sys
from pathlib import Path

# Scenes per preset (the image side is DATASET_SIDE in pipelines/presets.mk).
PRESETS = {
    "quick": 24,
    "full": 240,
}
MESHES = Path(__file__).resolve().parent.parent / "scenes" / "meshes"


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
        return v3(*t)
    return v3(1.0, rng.uniform(0.75, 1.0), rng.uniform(0.5, 1.0))


def scene(preset, index, seed, side, scene_dir=None):
    rng = random.Random(seed * 1_000_003 + index)
    w, h, d = rng.uniform(3.0, 7.0), rng.uniform(2.4, 3.6), rng.uniform(3.0, 7.0)
    materials, objects, lights = {}, [], []

    def material(kind=None):
        name = f"m{len(materials)}"
        kind = kind or rng.choices(["lambert", "glossy", "mirror", "glass"], [0.62, 0.26, 0.06, 0.06])[0]
        if kind == "lambert":
            materials[name] = f"Lambertian(reflectance: {color(rng)})"
        elif kind == "glossy":
            dif = rng.uniform(0.05, 0.5)
            spec = rng.uniform(0.1, 0.9 - dif)
            materials[name] = (
                f"Glossy(diffuse: {v3(dif, dif * rng.uniform(0.7, 1.0), dif * rng.uniform(0.5, 1.0))}, "
                f"specular: {v3(spec, spec, spec)}, roughness: {f(rng.uniform(0.08, 0.7))})"
            )
        elif kind == "mirror":
            r = rng.uniform(0.7, 0.95)
            materials[name] = f"Mirror(reflectance: {v3(r, r, r)})"
        else:
            materials[name] = f"Dielectric(ior: {f(rng.uniform(1.33, 1.7))})"
        return name

    # The room: six quads, faces towards the inside.
    walls = [
        ("floor", v3(0, 0, d), v3(w, 0, 0), v3(0, 0, -d)),
        ("ceiling", v3(0, h, 0), v3(w, 0, 0), v3(0, 0, d)),
        ("back", v3(0, 0, d), v3(0, h, 0), v3(w, 0, 0)),
        ("front", v3(0, 0, 0), v3(w, 0, 0), v3(0, h, 0)),
        ("left", v3(0, 0, 0), v3(0, h, 0), v3(0, 0, d)),
        ("right", v3(w, 0, 0), v3(0, 0, d), v3(0, h, 0)),
    ]
    # A quarter of the rooms are open at the front and seen from outside, as the Cornell box is:
    # the views then include empty background (no hit: zero radiance, albedo and normal).
    open_front = rng.random() < 0.25
    for name, corner, u, v in walls:
        if open_front and name == "front":
            continue
        objects.append(
            f'(name: "{name}", shape: Quad(corner: {corner}, u: {u}, v: {v}), material: "{material("lambert")}")'
        )

    # Furniture.
    targets = []
    for k in range(rng.randint(2, 7)):
        x, z = rng.uniform(0.6, w - 0.6), rng.uniform(0.6, d - 0.6)
        targets.append((x, z))
        kind = rng.choice(["table", "block", "sphere", "mesh", "cabinet"])
        m = material()
        if kind == "table":
            tw, td, th = rng.uniform(0.6, 1.6), rng.uniform(0.5, 1.0), rng.uniform(0.6, 0.9)
            objects.append(
                f'(name: "table{k}", shape: Box(size: {v3(tw, 0.05, td)}), transform: (translate: {v3(x, th, z)}), material: "{m}")'
            )
            for dx in (-1, 1):
                for dz in (-1, 1):
                    objects.append(
                        f'(shape: Box(size: {v3(0.05, th, 0.05)}), transform: (translate: {v3(x + dx * (tw / 2 - 0.05), th / 2, z + dz * (td / 2 - 0.05))}), material: "{m}")'
                    )
        elif kind in ("block", "cabinet"):
            s = v3(rng.uniform(0.2, 1.2), rng.uniform(0.2, 1.8 if kind == "cabinet" else 0.8), rng.uniform(0.2, 1.0))
            hgt = float(s.split(",")[1])
            objects.append(
                f'(name: "{kind}{k}", shape: Box(size: {s}), transform: (rotate_deg: {v3(0, rng.uniform(0, 90), 0)}, translate: {v3(x, hgt / 2, z)}), material: "{m}")'
            )
        elif kind == "sphere":
            r = rng.uniform(0.1, 0.5)
            objects.append(
                f'(name: "sphere{k}", shape: Sphere(radius: {f(r)}, subdivisions: 3), transform: (translate: {v3(x, r, z)}), material: "{m}")'
            )
        else:
            mesh = rng.choice(["torus.obj", "trefoil.glb"])
            # Relative to the scene file, so the generated text does not depend on the checkout.
            rel = os.path.relpath(MESHES / mesh, scene_dir) if scene_dir else str(MESHES / mesh)
            shape = f'Obj(path: "{rel}")' if mesh.endswith(".obj") else f'Gltf(path: "{rel}")'
            sc = rng.uniform(0.6, 1.5)
            objects.append(
                f'(name: "mesh{k}", shape: {shape}, transform: (scale: {v3(sc, sc, sc)}, rotate_deg: {v3(rng.uniform(0, 90), rng.uniform(0, 360), 0)}, translate: {v3(x, rng.uniform(0.3, 1.2), z)}), material: "{m}")'
            )

    # Emitters: at least one, of several kinds.
    emitter_material = material("lambert")
    for k in range(rng.randint(1, 4)):
        kind = rng.choices(["panel", "bulb", "point"], [0.5, 0.3, 0.2])[0]
        tint = light_tint(rng)
        if kind == "panel":
            pw, pd = rng.uniform(0.2, 1.5), rng.uniform(0.2, 1.5)
            px, pz = rng.uniform(0.2, w - pw - 0.2), rng.uniform(0.2, d - pd - 0.2)
            objects.append(
                f'(name: "panel{k}", shape: Quad(corner: {v3(px, h - 0.01, pz)}, u: {v3(pw, 0, 0)}, v: {v3(0, 0, pd)}), '
                f'material: "{emitter_material}", emission: Flux(lumens: {f(rng.uniform(500, 6000))}, color: {tint}))'
            )
        elif kind == "bulb":
            # Small and bright: the caustic and firefly makers.
            r = rng.uniform(0.02, 0.08)
            objects.append(
                f'(name: "bulb{k}", shape: Sphere(radius: {f(r)}, subdivisions: 2), transform: (translate: {v3(rng.uniform(0.3, w - 0.3), rng.uniform(0.5, h - 0.3), rng.uniform(0.3, d - 0.3))}), '
                f'material: "{emitter_material}", emission: Flux(lumens: {f(rng.uniform(200, 3000))}, color: {tint}))'
            )
        else:
            lights.append(
                f"(position: {v3(rng.uniform(0.3, w - 0.3), rng.uniform(0.5, h - 0.2), rng.uniform(0.3, d - 0.3))}, power: Flux({f(rng.uniform(300, 3000))}), color: {tint})"
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
    mats = ",\n        ".join(f'"{k}": {v}' for k, v in materials.items())
    objs = ",\n        ".join(objects)
    lts = ",\n        ".join(lights)
    return f"""// Generated by data-gen/generate.py --preset {preset} (scene {index}, seed {seed}).
Scene(
    camera: Camera(position: {cam}, look_at: {look}, vfov_deg: {f(rng.uniform(45, 75))}, resolution: ({side}, {side})),
    materials: {{
        {mats},
    }},
    objects: [
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
    ap.add_argument("--list", action="store_true")
    args = ap.parse_args()
    if args.scenes is not None and not 6 <= args.scenes <= 100_000:
        ap.error(f"--scenes {args.scenes}: expected 6 to 100000 (at least one scene per split)")
    scenes = names(args.preset, args.scenes)
    if args.list:
        print(" ".join(f"{s}/{n}" for s, n in scenes))
        return
    if args.out is None:
        ap.error("--out is required unless --list")
    if args.side is None or not 16 <= args.side <= 8192:
        ap.error("--side: the image side in pixels, 16 to 8192, is required with --out")
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
