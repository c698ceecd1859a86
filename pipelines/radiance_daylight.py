"""Radiance as the peer of luxest's daylight: the same room with its windows, the same sky
(gensky), the same work-plane points, illuminance by `rtrace -I`; and the comparison report.

    .venv-peers/bin/python pipelines/radiance_daylight.py --scene scenes/daylit-room.ron \
        --info build/daylit-room/scene.info.ron -o reports/lighting/daylight/daylit-room.radiance.csv
    .venv-peers/bin/python pipelines/radiance_daylight.py report --dir reports/lighting/daylight \
        --case daylit-room build/daylit-room/daylit-room.sensors.ron ...

Run by `make lighting-daylight` (needs `scripts/setup.sh --peers`: PyPI pyradiance). What it
reads, so that nothing is typed twice:

- geometry and reflectances from the scene file (pipelines/radiance_office.py's reader and
  exporter), the windows cut out of their wall quads here, independently of luxest: each wall
  quad holding windows becomes the rectangles of the grid the windows' edges draw, without the
  openings;
- the sky from the scene's `Environment::Sky`, turned into gensky's arguments here (month day
  hour -a -o -m, or -ang; -c/-u/+s/-s/+i/-i; -B or -b in W/m² = lx / 179; -t; -g) and rendered
  by gensky with skybright.cal, as a `skyfunc glow` sky hemisphere (source 0 0 1 180) and
  ground hemisphere (0 0 -1 180), Radiance's standard daylight model; the sun as gensky writes
  it (`solar source sun ... 0.5`);
- the grid points from the compiled header's sensor sets.

Coordinates: luxest y-up → Radiance (x, -z, y), so luxest's default sky north (−z) is
Radiance's +y, gensky's north. Illuminance: 179 × (0.265 R + 0.670 G + 0.065 B) of rtrace -I.

Settings: the sky is a glow, reached only by ambient rays, so the interior's light is Radiance's
Monte Carlo ambient calculation: -aa 0 (no irradiance cache), -as 0, -ab 8 (each further bounce
adds < 0.1 % here), -ad 4096, -lw 1e-6, -lr -12, -dj 1 -ds 0.02 (the sun disk sampled, soft
penumbra as luxest's disk), -dt 0, -u+; every point REPEATS times, its value the mean and its
standard error the standard deviation over √REPEATS. The unobstructed horizontal illuminance
E_h is rtrace -I on the sky alone (a point looking up in an octree of the sky only), by the
same settings.

`report` compares luxest's sensor results (RON) with these CSVs point by point: a point agrees
when |E_luxest − E_Radiance| ≤ tol · E_Radiance + 3 √(σ_l² + σ_R²) (tol 2 % under the overcast
sky, 3 % with the sun), and writes `daylight.md` with the daylight-factor figures of both.
"""

import argparse
import itertools
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# Importing pyradiance puts the bundled Radiance binaries on PATH and sets RAYPATH.
import pyradiance

sys.path.insert(0, str(Path(__file__).resolve().parent))

from radiance_office import EFFICACY, WEIGHTS, add, polygon, quad_points, rad, read_ron

FLAGS = {"Overcast": "-c", "Uniform": "-u", "Clear": ("+s", "-s"), "Intermediate": ("+i", "-i")}


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def scale(a, s):
    return tuple(x * s for x in a)


def cut_windows(scene, path):
    """The scene's objects with each window's wall quad split around it (no transform but a
    translation on a quad holding a window)."""
    objects = [dict(o) for o in scene["objects"]]
    holes = {}
    for k, w in enumerate(scene.get("windows") or []):
        c, u, v = w["corner"], w["u"], w["v"]
        found = None
        for i, o in enumerate(objects):
            sh = o["shape"]
            if sh["__name__"] != "Quad":
                continue
            t = (o.get("transform") or {}).get("translate", [0.0, 0.0, 0.0])
            qc, qu, qv = add(sh["corner"], t), sh["u"], sh["v"]
            # The quad's edges are perpendicular in every scene exported here: s, t by projection.
            if abs(dot(qu, qv)) > 1e-9:
                continue
            pts = [c, add(c, u), add(c, v), add(add(c, u), v)]
            st = [(dot(sub(p, qc), qu) / dot(qu, qu), dot(sub(p, qc), qv) / dot(qv, qv)) for p in pts]
            normal = (qu[1] * qv[2] - qu[2] * qv[1], qu[2] * qv[0] - qu[0] * qv[2], qu[0] * qv[1] - qu[1] * qv[0])
            off = [abs(dot(sub(p, qc), normal)) / math.sqrt(dot(normal, normal)) for p in pts]
            if max(off) < 1e-6 and all(-1e-9 <= s <= 1 + 1e-9 and -1e-9 <= tt <= 1 + 1e-9 for s, tt in st):
                found = (i, qc, qu, qv, st)
                break
        if found is None:
            raise SystemExit(f"error: {path}: windows[{k}] lies in no wall quad")
        i, qc, qu, qv, st = found
        s0, s1 = min(p[0] for p in st), max(p[0] for p in st)
        t0, t1 = min(p[1] for p in st), max(p[1] for p in st)
        holes.setdefault(i, (qc, qu, qv, []))[3].append((s0, s1, t0, t1))
    out = []
    for i, o in enumerate(objects):
        if i not in holes:
            out.append(o)
            continue
        qc, qu, qv, hs = holes[i]
        ss = sorted({0.0, 1.0, *[h[0] for h in hs], *[h[1] for h in hs]})
        ts = sorted({0.0, 1.0, *[h[2] for h in hs], *[h[3] for h in hs]})
        n = 0
        for ta, tb in itertools.pairwise(ts):
            for sa, sb in itertools.pairwise(ss):
                sm, tm = (sa + sb) / 2, (ta + tb) / 2
                if any(h[0] < sm < h[1] and h[2] < tm < h[3] for h in hs):
                    continue
                n += 1
                corner = add(add(qc, scale(qu, sa)), scale(qv, ta))
                out.append(
                    {
                        "name": f"{o.get('name') or i}.{n}",
                        "shape": {
                            "__name__": "Quad",
                            "corner": corner,
                            "u": scale(qu, sb - sa),
                            "v": scale(qv, tb - ta),
                        },
                        "material": o["material"],
                    }
                )
    return out


def room_rad(scene, path):
    out = []
    for name, m in scene["materials"].items():
        if m.get("__name__") != "Lambertian":
            raise SystemExit(f"error: {path}: material {name!r}: only Lambertian is exported")
        r, g, b = m["reflectance"]
        out.append(f"void plastic {name}\n0\n0\n5 {r} {g} {b} 0 0\n")
    for k, o in enumerate(cut_windows(scene, path)):
        sh = o["shape"]
        if sh["__name__"] != "Quad":
            raise SystemExit(f"error: {path}: object {o.get('name')!r}: only quads are exported")
        t = (o.get("transform") or {}).get("translate", [0.0, 0.0, 0.0])
        out.append(polygon(o["material"], f"o{k}", quad_points(add(sh["corner"], t), sh["u"], sh["v"])))
    return "".join(out)


def gensky_args(scene, path):
    env = scene.get("environment")
    if not env or env.get("__name__") != "Sky":
        raise SystemExit(f"error: {path}: the scene has no Sky environment")
    sky = env["__tuple__"][0]
    up = sky.get("up", [0.0, 1.0, 0.0])
    north = sky.get("north", [0.0, 0.0, -1.0])
    if list(up) != [0.0, 1.0, 0.0] or list(north) != [0.0, 0.0, -1.0]:
        raise SystemExit(f"error: {path}: only the default sky frame (y up, north -z) is exported")
    kind = sky["kind"]["__name__"]
    flag = FLAGS[kind]
    if isinstance(flag, tuple):
        flag = flag[0] if sky.get("sun", True) else flag[1]
    if sky.get("date"):
        d = sky["date"]
        hour = ("+" if d.get("solar_time") else "") + f"{d['hour']}"
        args = [str(d["month"]), str(d["day"]), hour, "-a", str(d["latitude"]), "-o", str(d["longitude"])]
        args += ["-m", str(d["meridian"])]
    elif sky.get("angles"):
        args = ["-ang", str(sky["angles"]["altitude"]), str(sky["angles"]["azimuth"])]
    else:
        args = ["-ang", "90", "0"]
    args.append(flag)
    if sky.get("zenith_luminance") is not None:
        args += ["-b", repr(sky["zenith_luminance"] / EFFICACY)]
    elif sky.get("horizontal_illuminance") is not None:
        args += ["-B", repr(sky["horizontal_illuminance"] / EFFICACY)]
    else:
        args += ["-t", str(sky.get("turbidity", 2.45))]
    args += ["-g", str(sky.get("ground_reflectance", 0.2))]
    return args


SKY_GLOW = """
skyfunc glow sky_glow
0
0
4 1 1 1 0

sky_glow source sky
0
0
4 0 0 1 180

skyfunc glow ground_glow
0
0
4 1 1 1 0

ground_glow source ground
0
0
4 0 0 -1 180
"""


def settings(a):
    return [
        "-I",
        "-h",
        "-ab",
        str(a.ab),
        "-ad",
        str(a.ad),
        "-aa",
        "0",
        "-as",
        "0",
        "-dt",
        "0",
        "-dj",
        "1",
        "-ds",
        "0.02",
        "-lr",
        str(-(a.ab + 4)),
        "-lw",
        str(a.lw),
        "-u+",
        "-n",
        str(a.procs),
    ]


def rtrace(octree, rays, a, work):
    text = "\n".join(r for r in rays for _ in range(a.repeats)) + "\n"
    res = subprocess.run(
        ["rtrace", *settings(a), octree], input=text, capture_output=True, text=True, cwd=work, check=True
    )
    vals = [
        EFFICACY * sum(w * float(x) for w, x in zip(WEIGHTS, line.split()[:3]))
        for line in res.stdout.splitlines()
        if line.strip()
    ]
    if len(vals) != len(rays) * a.repeats:
        raise SystemExit(f"error: rtrace returned {len(vals)} values for {len(rays) * a.repeats} rays")
    out = []
    for n in range(len(rays)):
        v = vals[n * a.repeats : (n + 1) * a.repeats]
        mean = sum(v) / len(v)
        sd = math.sqrt(sum((x - mean) ** 2 for x in v) / (len(v) - 1))
        out.append((mean, sd / math.sqrt(len(v))))
    return out


def peer(a):
    scene, info = read_ron(a.scene), read_ron(a.info)
    sets = [s for s in info["sensors"] if s.get("calculation_grid")]
    if not sets:
        raise SystemExit(f"error: {a.info}: no calculation surface")
    gargs = gensky_args(scene, a.scene)
    t0 = time.time()
    with tempfile.TemporaryDirectory(prefix="luxest-daylight-") as tmp:
        work = Path(tmp)
        sky = subprocess.run(["gensky", *gargs], capture_output=True, text=True, check=True)
        (work / "sky.rad").write_text(sky.stdout + SKY_GLOW)
        (work / "room.rad").write_text(room_rad(scene, a.scene))
        for name, files in (("room.oct", ["sky.rad", "room.rad"]), ("sky.oct", ["sky.rad"])):
            with open(work / name, "wb") as f:
                subprocess.run(["oconv", *files], check=True, cwd=work, stdout=f)
        rays, index = [], []
        for s in sets:
            for k, p in enumerate(s["points"]):
                index.append((s["name"], k, p["position"]))
                rays.append(" ".join(f"{v:.9g}" for v in (*rad(p["position"]), *rad(p["normal"]))))
        vals = rtrace("room.oct", rays, a, work)
        (eh, eh_se) = rtrace("sky.oct", ["0 0 0 0 0 1"], a, work)[0]
    wall = time.time() - t0
    cpu = resource.getrusage(resource.RUSAGE_CHILDREN)
    version = subprocess.run(["rtrace", "-version"], check=True, capture_output=True, text=True).stdout.strip()
    header = [
        "# name: Radiance",
        f"# program: Radiance rtrace ({version}; PyPI pyradiance {pyradiance.__version__})",
        f"# sky: gensky {' '.join(gargs)}",
        f"# settings: rtrace {' '.join(settings(a))}, {a.repeats} evaluations per point",
        f"# horizontal_illuminance_lx: {eh!r}",
        f"# horizontal_illuminance_se_lx: {eh_se!r}",
        f"# cpu_seconds: {cpu.ru_utime + cpu.ru_stime:.1f}",
        f"# wall_seconds: {wall:.1f}",
        "set,index,x,y,z,illuminance_lx,standard_error_lx",
    ]
    rows = [f"{n},{k},{p[0]!r},{p[1]!r},{p[2]!r},{m!r},{se!r}" for (n, k, p), (m, se) in zip(index, vals)]
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp_out = out.with_suffix(".csv.tmp")
    tmp_out.write_text("\n".join(header + rows) + "\n")
    os.replace(tmp_out, out)
    print(f"radiance: wrote {out} ({len(rows)} points, E_h {eh:.1f} lx, {wall:.1f} s)", file=sys.stderr)


def read_peer(path):
    meta, rows = {}, []
    for line in Path(path).read_text().splitlines():
        if line.startswith("#"):
            key, _, val = line[1:].partition(":")
            meta[key.strip()] = val.strip()
        elif line and not line.startswith("set,"):
            f = line.split(",")
            rows.append((f[0], int(f[1]), tuple(map(float, f[2:5])), float(f[5]), float(f[6])))
    return meta, rows


def quantile(d, q):
    d = sorted(d)
    x = q * (len(d) - 1)
    i = math.floor(x)
    j = min(i + 1, len(d) - 1)
    return d[i] + (d[j] - d[i]) * (x - i)


def compare(lux_path, peer_path, tol):
    """Point-by-point agreement of luxest's sensor results with the peer's CSV: a dict of
    figures and the rows."""
    lux = read_ron(lux_path)
    meta, rows = read_peer(peer_path)
    pts = [p for s in lux["sets"] for p in s["points"]]
    if len(pts) != len(rows):
        raise SystemExit(f"error: {lux_path}: {len(pts)} points, {peer_path}: {len(rows)}")
    worst, fails, table = 0.0, 0, []
    for p, (_, _, pos, e_r, se_r) in zip(pts, rows):
        if max(abs(x - y) for x, y in zip(p["position"], pos)) > 1e-6:
            raise SystemExit(f"error: {lux_path}: point {p['position']} is not the peer's {pos}")
        diff = p["value"] - e_r
        allowed = tol * e_r + 3 * math.hypot(p["standard_error"], se_r)
        worst = max(worst, abs(diff) / allowed)
        fails += abs(diff) > allowed
        table.append((pos, p["value"], p["standard_error"], e_r, se_r, diff / e_r))
    eh_l = lux["sky"]["horizontal_illuminance_lux"]
    eh_r = float(meta["horizontal_illuminance_lx"])
    df_l = [100 * p["value"] / eh_l for p in pts]
    df_r = [100 * r[3] / eh_r for r in rows]
    sky = lux["sky"]["description"]
    try:  # radiance_office's RON reader decodes non-ASCII text byte by byte
        sky = sky.encode("latin-1").decode("utf-8")
    except UnicodeError:
        pass
    return {
        "sky": sky,
        "gensky": meta.get("sky", ""),
        "settings": meta.get("settings", ""),
        "eh": (eh_l, eh_r, float(meta["horizontal_illuminance_se_lx"])),
        "points": len(rows),
        "fails": fails,
        "worst": worst,
        "mean_rel": sum(t[5] for t in table) / len(table),
        "max_rel": max(abs(t[5]) for t in table),
        "df": {
            "luxest": (quantile(df_l, 0.5), quantile(df_l, 0.05), min(df_l)),
            "radiance": (quantile(df_r, 0.5), quantile(df_r, 0.05), min(df_r)),
        },
        "run": lux["run"],
        "cpu": meta.get("cpu_seconds", ""),
    }


def report(a):
    lines = [
        "# Daylight: luxest against Radiance",
        "",
        "Written by `make lighting-daylight` (pipelines/radiance_daylight.py). Each case: luxest's local",
        "estimate (`estimate sensors`) on the work plane of the scene, Radiance `rtrace -I` on the same",
        "room, sky and points. A point agrees when |E_luxest − E_Radiance| ≤ tol · E_Radiance + 3σ",
        "(σ: both standard errors combined); tol = 2 % under the overcast sky, 3 % with the sun.",
        "Daylight factor D = 100 E / E_h, E_h each program's own unobstructed horizontal illuminance",
        "of the sky (and sun); EN 17037 figures: the median (target D_T) and the value reached on",
        "95 % of the points (D_TM), and the minimum.",
        "",
    ]
    ok = True
    for name, lux_path, peer_path, tol in a.case:
        tol = float(tol)
        c = compare(lux_path, peer_path, tol)
        ok &= c["fails"] == 0
        eh_l, eh_r, eh_se = c["eh"]
        dl, dr = c["df"]["luxest"], c["df"]["radiance"]
        lines += [
            f"## {name}",
            "",
            f"- sky: {c['sky']}",
            f"- Radiance: {c['gensky']}; {c['settings']} ({c['cpu']} CPU s)",
            (
                f"- luxest: `estimate sensors` {c['run'].get('samples')} light paths, seed {c['run'].get('seed')}, "
                f"{c['run'].get('seconds', 0):.1f} s"
            ),
            (
                f"- E_h: luxest {eh_l:.1f} lx (the tabulated map's integral, sun included), Radiance "
                f"{eh_r:.1f} ± {eh_se:.1f} lx ({100 * (eh_l / eh_r - 1):+.2f} %)"
            ),
            (
                f"- {c['points']} points, tolerance {100 * tol:g} % + 3σ: **{c['points'] - c['fails']} agree**, "
                f"worst |Δ| / allowed {c['worst']:.2f}; mean relative difference {100 * c['mean_rel']:+.2f} %, "
                f"largest {100 * c['max_rel']:.2f} %"
            ),
            "",
            "| | median D % | D % on 95 % | min D % |",
            "|---|---|---|---|",
            f"| luxest | {dl[0]:.3f} | {dl[1]:.3f} | {dl[2]:.3f} |",
            f"| Radiance | {dr[0]:.3f} | {dr[1]:.3f} | {dr[2]:.3f} |",
            "",
        ]
    lines.append("Result: " + ("every point of every case agrees." if ok else "**some points disagree**."))
    out = Path(a.dir) / "daylight.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}", file=sys.stderr)
    if not ok:
        raise SystemExit("error: luxest and Radiance disagree (see the report)")


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "report":
        ap = argparse.ArgumentParser(description="compare luxest's daylight results with Radiance's")
        ap.add_argument("report")
        ap.add_argument("--dir", required=True)
        ap.add_argument(
            "--case", nargs=4, action="append", required=True, metavar=("NAME", "SENSORS_RON", "PEER_CSV", "TOL")
        )
        report(ap.parse_args())
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", required=True, help="the scene file (.ron)")
    ap.add_argument("--info", required=True, help="scene-compile --info output of the same scene")
    ap.add_argument("-o", "--out", required=True, help="peer CSV")
    ap.add_argument("--ab", type=int, default=8, help="ambient bounces")
    ap.add_argument("--ad", type=int, default=4096, help="ambient divisions")
    ap.add_argument("--lw", type=float, default=1e-6, help="ray weight limit")
    ap.add_argument("--repeats", type=int, default=8, help="independent evaluations per point")
    ap.add_argument("--procs", type=int, default=2, help="rtrace processes (-n)")
    peer(ap.parse_args())


if __name__ == "__main__":
    main()
