"""Reference values of Mitsuba 3's BSDFs for luxest's materials (`crates/render/src/bsdf/`).

Run with the peers' environment (Mitsuba 3, variant scalar_rgb):

    /work/main/.venv-peers/bin/python crates/render/tests/data/mitsuba_bsdf.py

It writes `mitsuba_bsdf.ron` next to itself: for each case, the luxest material (RON, as a
scene file writes it) and rows computed by Mitsuba on the same BSDF in the local frame (+z the
normal; luxest's `wo` is Mitsuba's `si.wi`, luxest's `wi` Mitsuba's `wo`):

- `Eval`: Mitsuba's `eval` (f times |cos θ| of the new direction) and `pdf` at fixed directions;
- `Sample`: Mitsuba's `sample` for fixed uniform numbers (u, uc): the direction, the weight
  f |cos| / pdf and the pdf (zero weight: Mitsuba's sample is invalid).

`Radiance` rows use Mitsuba's radiance transport, `Flux` rows its importance transport.
The Rust test `bsdf::tests::agrees_with_mitsuba` compares luxest's eval, pdf and sample with them.
"""

import math
import os

import mitsuba as mi

mi.set_variant("scalar_rgb")


def rgb(c):
    return {"type": "rgb", "value": list(c)}


def norm(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def ron_rgb(c):
    return "(%r, %r, %r)" % tuple(float(x) for x in c)


def ron_rough(d, a):
    return "Some((distribution: %s, alpha: %r))" % (d, a)


def conductor(eta, k, spec, dist=None, alpha=None):
    m = {
        "type": "conductor" if dist is None else "roughconductor",
        "eta": rgb(eta),
        "k": rgb(k),
        "specular_reflectance": rgb(spec),
    }
    ron = "Conductor(eta: %s, k: %s, specular_reflectance: %s" % (ron_rgb(eta), ron_rgb(k), ron_rgb(spec))
    if dist is not None:
        m["distribution"] = dist.lower()
        m["alpha"] = alpha
        ron += ", roughness: " + ron_rough(dist, alpha)
    return m, ron + ")"


def plastic(diffuse, spec, ior, nonlinear, dist=None, alpha=None):
    m = {
        "type": "plastic" if dist is None else "roughplastic",
        "diffuse_reflectance": rgb(diffuse),
        "specular_reflectance": rgb(spec),
        "int_ior": ior,
        "ext_ior": 1.0,
        "nonlinear": nonlinear,
    }
    ron = "Plastic(diffuse_reflectance: %s, specular_reflectance: %s, ior: %r, nonlinear: %s" % (
        ron_rgb(diffuse),
        ron_rgb(spec),
        ior,
        "true" if nonlinear else "false",
    )
    if dist is not None:
        m["distribution"] = dist.lower()
        m["alpha"] = alpha
        ron += ", roughness: " + ron_rough(dist, alpha)
    return m, ron + ")"


def rough_dielectric(ior, dist, alpha):
    m = {"type": "roughdielectric", "int_ior": ior, "ext_ior": 1.0, "distribution": dist.lower(), "alpha": alpha}
    return m, "RoughDielectric(ior: %r, roughness: (distribution: %s, alpha: %r))" % (ior, dist, alpha)


def thin_dielectric(ior):
    return ({"type": "thindielectric", "int_ior": ior, "ext_ior": 1.0}, "ThinDielectric(ior: %r)" % ior)


def diffuse(c):
    return {"type": "diffuse", "reflectance": rgb(c)}, "Lambertian(reflectance: %s)" % ron_rgb(c)


def blend(w, a, b):
    return (
        {"type": "blendbsdf", "weight": w, "first": a[0], "second": b[0]},
        "Blend(weight: %r, first: %s, second: %s)" % (w, a[1], b[1]),
    )


GOLD = ([0.143, 0.374, 1.442], [3.983, 2.385, 1.603])

CASES = [
    ("smooth conductor", conductor(*GOLD, [1, 1, 1])),
    ("rough conductor GGX", conductor(*GOLD, [1, 1, 1], "Ggx", 0.3)),
    ("rough conductor Beckmann", conductor([1.5, 0.9, 0.4], [2.0, 3.0, 4.5], [0.9, 0.8, 0.7], "Beckmann", 0.2)),
    ("smooth plastic", plastic([0.6, 0.3, 0.1], [1, 1, 1], 1.5, False)),
    ("smooth plastic nonlinear", plastic([0.2, 0.5, 0.8], [0.8, 0.8, 0.8], 1.49 / 1.000277, True)),
    ("rough plastic GGX", plastic([0.6, 0.3, 0.1], [1, 1, 1], 1.5, False, "Ggx", 0.25)),
    ("rough plastic Beckmann nonlinear", plastic([0.2, 0.5, 0.8], [0.8, 0.8, 0.8], 1.6, True, "Beckmann", 0.4)),
    ("rough dielectric GGX", rough_dielectric(1.5, "Ggx", 0.3)),
    ("rough dielectric Beckmann", rough_dielectric(1.33, "Beckmann", 0.15)),
    ("thin dielectric", thin_dielectric(1.5)),
    ("blend", blend(0.3, conductor(*GOLD, [1, 1, 1], "Ggx", 0.2), diffuse([0.7, 0.5, 0.3]))),
]

# (wo, wi) pairs: reflection above, and transmission for the transmitting models.
OUTSIDE = [norm(v) for v in ([0.3, 0.2, 0.9], [0.8, -0.1, 0.5], [-0.95, 0.1, 0.25], [0.0, 0.0, 1.0])]
REFLECTED = [norm(v) for v in ([-0.2, -0.25, 0.9], [0.1, 0.5, 0.8], [-0.7, 0.1, 0.6], [0.85, 0.0, 0.3])]
TRANSMITTED = [norm(v) for v in ([-0.2, -0.1, -0.95], [0.3, 0.4, -0.8], [-0.6, 0.05, -0.7])]
UNIFORM = [(0.12, 0.34, 0.05), (0.7, 0.2, 0.5), (0.45, 0.81, 0.93), (0.9, 0.6, 0.3), (0.33, 0.05, 0.71)]


def si_for(wo):
    si = mi.SurfaceInteraction3f()
    si.p = [0, 0, 0]
    si.n = [0, 0, 1]
    si.sh_frame = mi.Frame3f(si.n)
    si.uv = [0.5, 0.5]
    si.wi = wo
    return si


def vec(v):
    return "(%r, %r, %r)" % tuple(float(x) for x in v)


def row(kind, mode, wo, wi, u, uc, value, pdf):
    return "(kind: %s, mode: %s, wo: %s, wi: %s, u: (%r, %r), uc: %r, value: %s, pdf: %r)" % (
        kind,
        mode,
        vec(wo),
        vec(wi),
        u[0],
        u[1],
        uc,
        vec(value),
        float(pdf),
    )


def rows_of(bsdf, transmits):
    rows = []
    modes = [("Radiance", mi.TransportMode.Radiance)]
    if transmits:
        modes.append(("Flux", mi.TransportMode.Importance))
    wos = OUTSIDE + ([[-x for x in v] for v in OUTSIDE[:2]] if transmits else [])
    for name, mode in modes:
        ctx = mi.BSDFContext(mode)
        for wo in wos:
            si = si_for(wo)
            targets = REFLECTED + (TRANSMITTED if transmits else [])
            for wi in targets:
                if wo[2] < 0:
                    wi = [-x for x in wi]
                rows.append(row("Eval", name, wo, wi, (0.0, 0.0), 0.0, bsdf.eval(ctx, si, wi), bsdf.pdf(ctx, si, wi)))
            if wo[2] > 0:
                for u1, u2, uc in UNIFORM:
                    bs, w = bsdf.sample(ctx, si, uc, [u1, u2])
                    rows.append(row("Sample", name, wo, bs.wo, (u1, u2), uc, w, bs.pdf))
    return rows


def main():
    out = [
        "// Mitsuba %s (scalar_rgb) reference values of the luxest materials, written by" % mi.__version__,
        "// crates/render/tests/data/mitsuba_bsdf.py; see its docstring.",
        "[",
    ]
    for name, (m, ron) in CASES:
        bsdf = mi.load_dict(m)
        transmits = m["type"] in ("roughdielectric", "thindielectric")
        out.append("  (name: %r, material: %s, rows: [" % (name, ron))
        out.extend("    %s," % r for r in rows_of(bsdf, transmits))
        out.append("  ]),")
    out.append("]")
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "mitsuba_bsdf.ron")
    with open(path, "w") as f:
        f.write("\n".join(out).replace("'", '"') + "\n")


if __name__ == "__main__":
    main()
