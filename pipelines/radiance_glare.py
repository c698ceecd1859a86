"""Radiance `evalglare` as the peer of luxest's UGR at the scene's observers: the same room
rendered by `rpict` as a 180 degree angular fisheye (-vta) from each observer's eye along each
line of sight, evaluated by `evalglare`, beside luxest's `estimate sensors` glare results.

    .venv-peers/bin/python pipelines/radiance_glare.py --scene scenes/office.ron \
        --info build/office/scene.info.ron --luxest build/office/office.sensors.ron \
        -o reports/lighting/glare/office.md

Run by `make lighting-glare` (needs `scripts/setup.sh --peers`). The room (geometry, Lambertian
materials) and the RON reader come from pipelines/radiance_office.py. The luminaires differ from
that script's far-field spheres, because glare needs the luminous area: each is `ies2rad`'s
light source of the file's luminous opening (`ies2rad -dm` without -i: a rectangle or disk with
the tabulated distribution over its projected area, so its luminance towards the eye is I / A_p,
as luxest's). A flat opening emits downwards only; the upward part of a distribution (the
direct/indirect pendant's) is a separate 5 mm `illum` sphere with the upper half of the table,
invisible to view rays, so the room is lit as luxest lights it and the eye sees the opening.
An EULUMDAT file is converted into IES LM-63-2002 here with its luminous area (lines 16, 17).

evalglare: -b THRESHOLD (cd/m^2; default 1000, above every room surface and below every
luminaire seen in these rooms) makes the luminaires the glare sources, as CIE 117 does; its
other settings are its defaults (background (E_v - E_dir)/pi as CIE 117, Guth position index
above and Iwata's below the line of sight, capped at 16, smoothing and peak extraction). The
report gives per observer and view luxest's UGR +- its standard error, evalglare's UGR, the
difference, and both background luminances; the check is |dUGR| <= 1.
"""

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pyradiance  # the bundled Radiance binaries on PATH, RAYPATH set

sys.path.insert(0, str(Path(__file__).resolve().parent))
import radiance_office as ro

EFFICACY = 179.0


def ies_text(name, g, c, planes, width, length):
    lines = [
        "IESNA:LM-63-2002",
        f"[TEST] {name}: converted by pipelines/radiance_glare.py",
        "TILT=NONE",
        f"1 -1 1 {len(g)} {len(c)} 1 2 {width:.6g} {length:.6g} 0",
        "1 1 0",
        " ".join(f"{x:g}" for x in g),
        " ".join(f"{x:g}" for x in c),
    ] + [" ".join(f"{x:.9g}" for x in p) for p in planes]
    return "\n".join(lines) + "\n"


def read_ies_table(path):
    """(gamma, C, planes, width, length) of an IES LM-63 file (metres, absolute cd)."""
    text = Path(path).read_text(errors="replace").splitlines()
    k = next(i for i, line in enumerate(text) if line.startswith("TILT="))
    nums = [float(x) for line in text[k + 1 :] for x in line.replace(",", " ").split()]
    _n, _lm, mult, ng, nc, _pt, units, width, length, _h = nums[:10]
    ballast = nums[10]
    ng, nc = int(ng), int(nc)
    rest = nums[13:]
    g, c = rest[:ng], rest[ng : ng + nc]
    vals = rest[ng + nc : ng + nc + ng * nc]
    planes = [[v * mult * ballast for v in vals[i * ng : (i + 1) * ng]] for i in range(nc)]
    scale = 0.3048 if units == 1 else 1.0
    return g, c, planes, width * scale, length * scale


def luminaire_sources(source, name):
    """IES texts (visible opening with the downward half; invisible upward half or None)."""
    if source.suffix.lower() == ".ldt":
        c, g, cd, isym = ro.read_ldt(source)
        if isym == 0:
            c, cd = c + [360.0], cd + [cd[0]]
        lines = source.read_text(errors="replace").splitlines()
        length, width = float(lines[15]) / 1000.0, float(lines[16]) / 1000.0
    else:
        g, c, cd, width, length = read_ies_table(source)
    down = [[v if gg < 90.0 else 0.0 for gg, v in zip(g, p)] for p in cd]
    up = [[v if gg > 90.0 else 0.0 for gg, v in zip(g, p)] for p in cd]
    has_up = any(v > 0 for p in up for v in p)
    return (
        ies_text(name, g, c, down, width, length),
        ies_text(name, g, c, up, 0.0, 0.0) if has_up else None,
    )


def luminaires_rad(scene_path, info, work):
    out = []
    for e, rz, source in ro.luminaire_placements(scene_path, info):
        down, up = luminaire_sources(source, e["name"])
        x, y, z = ro.rad(e["position"])
        for part, text, extra in [("d", down, []), ("u", up, ["-i", "0.005"])]:
            if text is None:
                continue
            stem = f"{e['name']}_{part}"
            (work / f"{stem}.ies").write_text(text)
            cmd = [
                "ies2rad",
                "-dm",
                "-c",
                "1",
                "1",
                "1",
                *extra,
                "-m",
                repr(e["multiplier"]),
                "-l",
                str(work),
                "-o",
                stem,
                f"{stem}.ies",
            ]
            subprocess.run(cmd, check=True, cwd=work, capture_output=True)
            if part == "u":  # invisible to view rays: light -> illum without an alternate
                r = (work / f"{stem}.rad").read_text()
                (work / f"{stem}.rad").write_text(re.sub(r"\blight\b", "illum", r))
            out.append(f"!xform -rz {rz:.9g} -t {x:.9g} {y:.9g} {z:.9g} {stem}.rad\n")
    return "".join(out)


def evalglare(pic, threshold):
    r = subprocess.run(["evalglare", "-b", str(threshold), "-d", str(pic)], capture_output=True, text=True, check=True)
    # The detailed output ends with "dgp,av_lum,E_v,lum_backg,E_v_dir,dgi,ugr,...: values".
    for line in r.stdout.splitlines():
        if line.startswith("dgp,") and ":" in line:
            keys, vals = line.split(":", 1)
            return dict(zip(keys.split(","), (float(v) for v in vals.split())))
    raise SystemExit(f"error: evalglare gave no result for {pic}:\n{r.stdout}\n{r.stderr}")


def render(a, scene, info, glare, settings):
    """evalglare's numbers for every observer and view (rpict -vta from each eye)."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        (work / "room.rad").write_text(ro.scene_rad(scene, a.scene))
        (work / "lum.rad").write_text(luminaires_rad(a.scene, info, work))
        with open(work / "scene.oct", "wb") as f:
            subprocess.run(["oconv", "room.rad", "lum.rad"], check=True, cwd=work, stdout=f)
        for k, g in enumerate(glare):
            eye, view = ro.rad(g["position"]), ro.rad(g["view"])
            pic = work / f"view{k}.hdr"
            with open(pic, "wb") as f:
                subprocess.run(
                    [
                        "rpict",
                        *settings,
                        "-af",
                        "scene.amb",
                        "-vta",
                        "-vp",
                        *map(str, eye),
                        "-vd",
                        *map(str, view),
                        "-vu",
                        "0",
                        "0",
                        "1",
                        "-vh",
                        "180",
                        "-vv",
                        "180",
                        "scene.oct",
                    ],
                    check=True,
                    cwd=work,
                    stdout=f,
                )
            ev = evalglare(pic, a.threshold)
            rows.append((g, ev))
            print(f"{g['observer']} {g['view']}: luxest {g['ugr']:.2f} evalglare {ev['ugr']:.2f}", file=sys.stderr)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", required=True)
    ap.add_argument("--info", required=True)
    ap.add_argument("--luxest", required=True, help="estimate sensors results with glare")
    ap.add_argument("-o", "--out", required=True, help="Markdown report; a CSV is written beside")
    ap.add_argument("--res", type=int, default=500, help="fisheye pixels per side")
    ap.add_argument("--threshold", type=float, default=1000.0, help="evalglare -b, cd/m^2")
    ap.add_argument("--ab", type=int, default=4)
    ap.add_argument("--ad", type=int, default=1024)
    ap.add_argument("--aa", type=float, default=0.15)
    ap.add_argument(
        "--reuse",
        help="a CSV this script wrote before for the same room: compare with its evalglare "
        "numbers instead of rendering again (its settings line is kept)",
    )
    a = ap.parse_args()
    scene = ro.read_ron(a.scene)
    info = ro.read_ron(a.info)
    lux = ro.read_ron(a.luxest)
    glare = lux.get("glare") or []
    if not glare:
        raise SystemExit(f"error: {a.luxest}: no glare results (does the scene have observers?)")
    settings = [
        "-ab",
        str(a.ab),
        "-ad",
        str(a.ad),
        "-as",
        str(a.ad // 4),
        "-aa",
        str(a.aa),
        "-ar",
        "128",
        "-lw",
        "1e-4",
        "-ds",
        "0.02",
        "-dj",
        "0",
        "-ps",
        "1",
        "-pj",
        "0",
        "-dt",
        "0",
        "-x",
        str(a.res),
        "-y",
        str(a.res),
    ]
    rows = []
    t0 = time.time()
    previous = None
    if a.reuse:
        lines = Path(a.reuse).read_text().splitlines()
        previous = [dict(zip(lines[0].split(","), line.split(","))) for line in lines[1:]]
        if len(previous) != len(glare):
            raise SystemExit(f"error: {a.reuse}: {len(previous)} views, the results have {len(glare)}")
        for g, prev in zip(glare, previous):
            if prev["observer"] != g["observer"]:
                raise SystemExit(f"error: {a.reuse}: observer {prev['observer']} is not {g['observer']}")
            ev = {"ugr": float(prev["ugr_evalglare"]), "lum_backg": float(prev["lb_evalglare"])}
            rows.append((g, dict(ev, E_v=float(prev["ev_evalglare"]))))
    else:
        rows = render(a, scene, info, glare, settings)
    seconds = time.time() - t0
    out = Path(a.out)
    csv = ["observer,view_x,view_y,view_z,ugr_luxest,ugr_luxest_se,ugr_evalglare,lb_luxest,lb_evalglare,ev_evalglare"]
    md = [
        f"# Glare (UGR): luxest against Radiance evalglare, scene `{a.scene}`",
        "",
        (
            f"Written by `pipelines/radiance_glare.py` ({time.strftime('%Y-%m-%d')}): rpict "
            f"`{' '.join(settings)} -vta -vh 180 -vv 180` from each eye, evalglare `-b "
            f"{a.threshold:g} -d` (Radiance from PyPI pyradiance {pyradiance.__version__}); "
            f"luxest: `{a.luxest}` ({lux['run']['samples']} light paths). "
            + (
                f"evalglare numbers reused from `{a.reuse}` (rendered with these settings)."
                if a.reuse
                else f"{seconds:.0f} s of Radiance."
            )
        ),
        "",
        "| observer | view | UGR luxest | UGR evalglare | Δ | L_b luxest (cd/m²) | L_b evalglare | luxest sources | |ΔUGR| ≤ 1 |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    worst = 0.0
    for g, ev in rows:
        v = g["view"]
        d = g["ugr"] - ev["ugr"]
        worst = max(worst, abs(d))
        lb = g["background_luminance"]["value"]
        md.append(
            f"| {g['observer']} | ({v[0]:g}, {v[1]:g}, {v[2]:g}) | {g['ugr']:.2f} ± "
            f"{g['standard_error']:.2f} | {ev['ugr']:.2f} | {d:+.2f} | {lb:.1f} | "
            f"{ev['lum_backg']:.1f} | {len(g['sources'])} "
            f"| {'yes' if abs(d) <= 1 else 'NO'} |"
        )
        csv.append(
            f"{g['observer']},{v[0]},{v[1]},{v[2]},{g['ugr']:.4f},{g['standard_error']:.4f},"
            f"{ev['ugr']:.4f},{lb:.4f},{ev['lum_backg']:.4f},{ev['E_v']:.4f}"
        )
    md += ["", f"Largest |ΔUGR|: {worst:.2f} ({'within' if worst <= 1 else 'OUTSIDE'} ±1)."]
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(md) + "\n")
    out.with_suffix(".csv").write_text("\n".join(csv) + "\n")
    print(f"wrote {out}: largest |dUGR| {worst:.2f}", file=sys.stderr)


if __name__ == "__main__":
    main()
