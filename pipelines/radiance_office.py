"""Radiance as the peer of luxest's lighting report: the same room, the same luminaire
tables, the same work-plane points, illuminance by `rtrace -I`.

    .venv-peers/bin/python pipelines/radiance_office.py --scene scenes/office.ron \
        --info build/office/scene.info.ron -o reports/lighting/office/radiance.csv

Run by `make lighting-radiance` (needs `scripts/setup.sh --peers`: PyPI pyradiance, which bundles
the Radiance binaries). What it reads, so that nothing is typed twice:

- geometry and materials from the scene file (`Quad` and `Box` shapes with translations;
  `Lambertian` reflectances become Radiance `plastic` with the same RGB reflectance, no
  specularity, no roughness);
- the luminaires' position, frame and multiplier from the compiled scene's header
  (`scene-compile --info`), their photometric files from the scene's directory, read
  independently of luxest: an IES file goes to `ies2rad` as it is; an EULUMDAT file is
  converted here into an equivalent IES LM-63-2002 file (`ldt_to_ies`: same angles, same
  symmetry, candela = cd/klm x conversion factor x lamp flux / 1000). `ies2rad -dm -i 0.005
  -c 1 1 1 -m <multiplier>` makes each an illum sphere of 5 mm radius with the tabulated
  distribution, white: a far-field source, as luxest's point-like luminaires;
- the grid points (positions and normals) from the same header's sensor sets.

Coordinates: luxest is y-up, Radiance z-up; a luxest point (x, y, z) is Radiance (x, -z, y), a
proper rotation, under which a luminaire aimed straight down keeps ies2rad's frame (C = 0 along
+x, C = 90 along +y, nadir -z).

Illuminance: rtrace -I gives irradiance per channel in W/m^2; Radiance's luminous efficacy
179 lm/W and its luminance weights 0.265/0.670/0.065 give lux (the sources are white, so the
channels are equal). Uncertainty: rtrace with -aa 0 (no irradiance cache: plain Monte Carlo
ambient sampling), -as 0 (no adaptive super-sampling), -dt 0 (every source tested for shadows,
none estimated statistically) and -u+ (uncorrelated random sampling) evaluates every point
REPEATS times in one run; the point's value is the mean of the repeats and its standard
error their standard deviation over sqrt(REPEATS). Radiance's defaults -as 512 and -dt 0.03
left a 0.3 % dip at one corner of the symmetric office. The defaults here (-ab 16 -ad 1024
-lw 1e-5 -lr -20, 8 repeats: about 65 CPU s) are converged: beyond -ab 8 -ad 512 -lw 1e-4 the
work plane's mean moves by about 0.1 % at most (docs/measurements.md has the series). The
CSV follows `report::peer` (comment lines, then `set,index,x,y,z,illuminance_lx,
standard_error_lx`) in luxest's coordinates.
"""

import argparse
import math
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pyradiance  # noqa: F401  (puts the bundled Radiance binaries on PATH, sets RAYPATH)

EFFICACY = 179.0  # lm/W, Radiance's white-light luminous efficacy (rpict/rtrace convention)
WEIGHTS = (0.265, 0.670, 0.065)  # Radiance's luminance weights of R, G, B
SPHERE_RADIUS = 0.005  # m, the illum sphere ies2rad puts in place of each luminaire


# --- A small RON reader (enough for scene files and `scene-compile --info`) -------------------

TOKEN = re.compile(
    r"""\s+|//[^\n]*|/\*.*?\*/|(?P<str>"(?:[^"\\]|\\.)*")|(?P<num>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"""
    r"""|(?P<id>[A-Za-z_][A-Za-z0-9_]*)|(?P<p>[()\[\]{}:,])""",
    re.S,
)


def tokens(text, path):
    pos, out = 0, []
    while pos < len(text):
        m = TOKEN.match(text, pos)
        if not m:
            line = text.count("\n", 0, pos) + 1
            raise SystemExit(f"error: {path}:{line}: cannot read RON at {text[pos : pos + 20]!r}")
        pos = m.end()
        for kind in ("str", "num", "id", "p"):
            if m.group(kind) is not None:
                out.append((kind, m.group(kind)))
    return out


class Ron:
    """RON values as Python: structs and maps -> dict (a struct's name under '__name__', an enum
    variant's name likewise), tuples and lists -> list, Some(x) -> x, None -> None."""

    def __init__(self, text, path):
        self.t, self.i, self.path = tokens(text, path), 0, path

    def peek(self):
        return self.t[self.i] if self.i < len(self.t) else (None, None)

    def take(self, value=None):
        tok = self.peek()
        if tok[0] is None or (value is not None and tok[1] != value):
            raise SystemExit(f"error: {self.path}: RON: expected {value!r}, found {tok[1]!r}")
        self.i += 1
        return tok

    def value(self):
        kind, tok = self.peek()
        if kind == "str":
            self.i += 1
            return bytes(tok[1:-1], "utf-8").decode("unicode_escape")
        if kind == "num":
            self.i += 1
            return float(tok) if any(c in tok for c in ".eE") else int(tok)
        if kind == "id":
            self.i += 1
            if tok in ("true", "false"):
                return tok == "true"
            if tok == "None":
                return None
            if self.peek()[1] == "(":
                inner = self.group("(", ")")
                if tok == "Some" and isinstance(inner, list) and len(inner) == 1:
                    return inner[0]
                if isinstance(inner, dict):
                    inner["__name__"] = tok
                    return inner
                return {"__name__": tok, "__tuple__": inner}
            return {"__name__": tok}
        if tok == "(":
            return self.group("(", ")")
        if tok == "[":
            return self.group("[", "]")
        if tok == "{":
            return self.group("{", "}")
        raise SystemExit(f"error: {self.path}: RON: unexpected {tok!r}")

    def group(self, open_, close):
        self.take(open_)
        items, fields = [], {}
        while self.peek()[1] != close:
            kind, tok = self.peek()
            nxt = self.t[self.i + 1][1] if self.i + 1 < len(self.t) else None
            if open_ == "(" and kind == "id" and nxt == ":":
                self.i += 2
                fields[tok] = self.value()
            elif open_ == "{":
                key = self.value()
                self.take(":")
                fields[key] = self.value()
            else:
                items.append(self.value())
            if self.peek()[1] == ",":
                self.i += 1
        self.take(close)
        return fields if (fields or open_ == "{") else items


def read_ron(path):
    return Ron(Path(path).read_text(), path).value()


# --- Geometry -----------------------------------------------------------------------------------


def rad(p):
    """luxest (x, y, z), y up -> Radiance (x, -z, y), z up."""
    return (p[0], -p[2], p[1])


def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def polygon(material, name, pts):
    coords = " ".join(f"{c:.9g}" for p in pts for c in rad(p))
    return f"{material} polygon {name}\n0\n0\n{3 * len(pts)} {coords}\n"


def quad_points(corner, u, v):
    return [corner, add(corner, u), add(add(corner, u), v), add(corner, v)]


def box_faces(size, t):
    hx, hy, hz = (s / 2 for s in size)
    c = lambda x, y, z: (t[0] + x, t[1] + y, t[2] + z)  # noqa: E731
    # Six faces, each counter-clockwise seen from outside.
    return [
        [c(-hx, -hy, -hz), c(-hx, -hy, hz), c(-hx, hy, hz), c(-hx, hy, -hz)],  # -x
        [c(hx, -hy, -hz), c(hx, hy, -hz), c(hx, hy, hz), c(hx, -hy, hz)],  # +x
        [c(-hx, -hy, -hz), c(hx, -hy, -hz), c(hx, -hy, hz), c(-hx, -hy, hz)],  # -y
        [c(-hx, hy, -hz), c(-hx, hy, hz), c(hx, hy, hz), c(hx, hy, -hz)],  # +y
        [c(-hx, -hy, -hz), c(-hx, hy, -hz), c(hx, hy, -hz), c(hx, -hy, -hz)],  # -z
        [c(-hx, -hy, hz), c(hx, -hy, hz), c(hx, hy, hz), c(-hx, hy, hz)],  # +z
    ]


def scene_rad(scene, path):
    out = []
    for name, m in scene["materials"].items():
        if m.get("__name__") != "Lambertian":
            raise SystemExit(f"error: {path}: material {name!r}: only Lambertian is exported")
        r, g, b = m["reflectance"]
        out.append(f"void plastic {name}\n0\n0\n5 {r} {g} {b} 0 0\n")
    for k, o in enumerate(scene["objects"]):
        name = o.get("name") or f"object{k}"
        tr = o.get("transform") or {}
        if set(tr) - {"translate", "__name__"}:
            raise SystemExit(f"error: {path}: object {name!r}: only translations are exported")
        t = tr.get("translate", [0.0, 0.0, 0.0])
        shape = o["shape"]
        if o.get("emission") is not None:
            raise SystemExit(f"error: {path}: object {name!r}: emitters are not exported")
        if shape["__name__"] == "Quad":
            pts = quad_points(add(shape["corner"], t), shape["u"], shape["v"])
            out.append(polygon(o["material"], name, pts))
        elif shape["__name__"] == "Box":
            for f, pts in enumerate(box_faces(shape["size"], t)):
                out.append(polygon(o["material"], f"{name}.{f}", pts))
        else:
            raise SystemExit(f"error: {path}: object {name!r}: shape {shape['__name__']} not exported")
    return "".join(out)


# --- Luminaires ---------------------------------------------------------------------------------


def read_ldt(path):
    """An EULUMDAT file read independently of luxest: (C angles, gamma angles, absolute cd per
    stored plane, symmetry indicator). Intensities are cd per 1000 lm of lamp flux; absolute
    candela are that times the conversion factor (line 24) times the total lamp flux of all lamp
    sets / 1000. Only the stored planes are returned (as the file gives them)."""
    lines = Path(path).read_text(errors="replace").splitlines()

    def num(i):  # 1-based line
        try:
            return float(lines[i - 1].replace(",", "."))
        except (IndexError, ValueError):
            raise SystemExit(f"error: {path}: line {i}: expected a number")

    isym, mc, ng = int(num(3)), int(num(4)), int(num(6))
    factor, n_sets = num(24), int(num(26))
    flux = sum(num(26 + 2 * n_sets + k + 1) for k in range(n_sets))  # each set's total flux
    at = 26 + 6 * n_sets + 10 + 1  # after the lamp sets and the 10 direct ratios
    c = [num(at + k) for k in range(mc)]
    g = [num(at + mc + k) for k in range(ng)]
    planes = {0: mc, 1: 1, 2: mc // 2 + 1, 4: mc // 4 + 1}
    if isym not in planes:
        raise SystemExit(f"error: {path}: line 3: symmetry Isym = {isym} is not converted (0, 1, 2, 4 are)")
    n = planes[isym]
    first = at + mc + ng
    if len(lines) < first + n * ng - 1:
        raise SystemExit(f"error: {path}: line {len(lines)}: truncated: {n * ng} intensities expected")
    scale = factor * flux / 1000.0
    cd = [[scale * num(first + p * ng + k) for k in range(ng)] for p in range(n)]
    return c[:n], g, cd, isym


def ldt_to_ies(ldt, ies):
    """An IES LM-63-2002 file (type C, absolute photometry) with the LDT file's distribution and
    its symmetry: Isym 1 -> one plane (rotational), 2 -> C 0..180 (bilateral), 4 -> C 0..90
    (quadrant), 0 -> C 0..360 (the C = 0 plane repeated at 360). Both formats put C = 0 along
    the luminaire's x axis, C = 90 along its y axis and gamma = 0 at nadir."""
    c, g, cd, isym = read_ldt(ldt)
    if isym == 0:
        c, cd = c + [360.0], cd + [cd[0]]
    lines = [
        "IESNA:LM-63-2002",
        f"[TEST] converted from {Path(ldt).name} by pipelines/radiance_office.py",
        "TILT=NONE",
        f"1 -1 1 {len(g)} {len(c)} 1 2 0 0 0",
        "1 1 0",
        " ".join(f"{x:g}" for x in g),
        " ".join(f"{x:g}" for x in c),
    ] + [" ".join(f"{x:.9g}" for x in plane) for plane in cd]
    Path(ies).write_text("\n".join(lines) + "\n")


def luminaire_placements(scene_path, info):
    """Each luminaire of the scene header `info` as (emitter, its turn about Radiance's z in
    degrees, its photometric file); only luminaires aimed straight down are exported."""
    P = ((1, 0, 0), (0, 0, -1), (0, 1, 0))
    base = Path(scene_path).parent
    for e in info["emitters"]:
        if e["__name__"] != "Luminaire":
            raise SystemExit(f"error: emitter {e['name']!r}: only luminaires are exported")
        m = e["frame"]
        # Radiance frame of the luminaire: P · M (see the module docs); must be a turn about z.
        pm = [[sum(P[r][k] * m[k][c] for k in range(3)) for c in range(3)] for r in range(3)]
        if abs(pm[2][2] - 1) > 1e-9:
            raise SystemExit(f"error: luminaire {e['name']!r}: only luminaires aimed straight down are exported")
        rz = math.degrees(math.atan2(pm[1][0], pm[0][0]))
        yield e, rz, base / info["photometries"][e["photometry"]]["source"]


def luminaires_rad(scene_path, info, work):
    """Each luminaire as an ies2rad illum sphere placed by its frame: an IES file as it is, an
    LDT file through ldt_to_ies; the multiplier through ies2rad -m."""
    out = []
    for e, rz, source in luminaire_placements(scene_path, info):
        ies = work / f"{e['name']}.ies"
        if source.suffix.lower() == ".ldt":
            ldt_to_ies(source, ies)
        else:
            ies.write_bytes(source.read_bytes())
        subprocess.run(
            [
                "ies2rad",
                "-dm",
                "-c",
                "1",
                "1",
                "1",
                "-i",
                str(SPHERE_RADIUS),
                "-m",
                repr(e["multiplier"]),
                "-l",
                str(work),
                "-o",
                e["name"],
                ies.name,
            ],
            check=True,
            cwd=work,
            capture_output=True,
        )
        x, y, z = rad(e["position"])
        out.append(f"!xform -rz {rz:.9g} -t {x:.9g} {y:.9g} {z:.9g} {e['name']}.rad\n")
    return "".join(out)


# --- The run ------------------------------------------------------------------------------------


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", required=True, help="the scene file (.ron)")
    ap.add_argument("--info", required=True, help="scene-compile --info output of the same scene")
    ap.add_argument("-o", "--out", required=True, help="peer CSV for `report --peer`")
    ap.add_argument("--ab", type=int, default=16, help="ambient bounces")
    ap.add_argument("--ad", type=int, default=1024, help="ambient divisions")
    ap.add_argument("--lw", type=float, default=1e-5, help="ray weight limit")
    ap.add_argument("--repeats", type=int, default=8, help="independent evaluations per point")
    ap.add_argument("--procs", type=int, default=2, help="rtrace processes (-n)")
    a = ap.parse_args()

    scene, info = read_ron(a.scene), read_ron(a.info)
    sets = [s for s in info["sensors"] if s.get("calculation_grid")]
    if not sets:
        raise SystemExit(f"error: {a.info}: no calculation surface")
    t0 = time.time()
    with tempfile.TemporaryDirectory(prefix="luxest-radiance-") as tmp:
        work = Path(tmp)
        (work / "room.rad").write_text(scene_rad(scene, a.scene))
        (work / "lum.rad").write_text(luminaires_rad(a.scene, info, work))
        with open(work / "office.oct", "wb") as oct_file:
            subprocess.run(["oconv", "room.rad", "lum.rad"], check=True, cwd=work, stdout=oct_file)
        rays, index = [], []
        for s in sets:
            for k, p in enumerate(s["points"]):
                o, d = rad(p["position"]), rad(p["normal"])
                index.append((s["name"], k, p["position"]))
                rays.append(" ".join(f"{v:.9g}" for v in (*o, *d)))
        text = "\n".join(r for r in rays for _ in range(a.repeats)) + "\n"
        # Unbiased settings where Radiance has a choice: no irradiance cache (-aa 0), no
        # adaptive super-sampling (-as 0), every source tested for shadows (-dt 0), and no
        # reflection limit below the ambient bounces (-lr).
        settings = [
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
            "-lr",
            str(-(a.ab + 4)),
            "-lw",
            str(a.lw),
            "-u+",
            "-n",
            str(a.procs),
        ]
        res = subprocess.run(
            ["rtrace", *settings, "office.oct"], input=text, capture_output=True, text=True, cwd=work, check=True
        )
    wall = time.time() - t0
    cpu = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu_s = cpu.ru_utime + cpu.ru_stime
    vals = [
        EFFICACY * sum(w * float(x) for w, x in zip(WEIGHTS, line.split()[:3]))
        for line in res.stdout.splitlines()
        if line.strip()
    ]
    if len(vals) != len(rays) * a.repeats:
        raise SystemExit(f"error: rtrace returned {len(vals)} values for {len(rays) * a.repeats} rays")
    rows = []
    for n, (name, k, p) in enumerate(index):
        v = vals[n * a.repeats : (n + 1) * a.repeats]
        mean = sum(v) / len(v)
        sd = math.sqrt(sum((x - mean) ** 2 for x in v) / (len(v) - 1))
        rows.append(f"{name},{k},{p[0]!r},{p[1]!r},{p[2]!r},{mean!r},{sd / math.sqrt(len(v))!r}")
    version = subprocess.run(["rtrace", "-version"], capture_output=True, text=True).stdout.strip()
    header = [
        "# name: Radiance",
        f"# program: Radiance rtrace ({version}; PyPI pyradiance {pyradiance.__version__})",
        f"# settings: rtrace {' '.join(settings)}, {a.repeats} evaluations per point; "
        f"ies2rad -dm -i {SPHERE_RADIUS} -c 1 1 1 -m <multiplier>",
        f"# cpu_seconds: {cpu_s:.1f}",
        f"# wall_seconds: {wall:.1f}",
        "# note: Geometry and reflectances from the scene file (Radiance plastic, no specularity); "
        "IES files as they are and the EULUMDAT file converted to IES by this script, each made by "
        f"ies2rad into a {SPHERE_RADIUS * 1000:g} mm illum sphere (far field, as luxest models them); each point's standard "
        f"error from {a.repeats} independent rtrace evaluations (-aa 0 -as 0 -dt 0, -u+).",
        "set,index,x,y,z,illuminance_lx,standard_error_lx",
    ]
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp_out = out.with_suffix(".csv.tmp")
    tmp_out.write_text("\n".join(header + rows) + "\n")
    os.replace(tmp_out, out)
    print(f"radiance: wrote {out} ({len(rows)} points, {cpu_s:.1f} CPU s, {wall:.1f} s)", file=sys.stderr)


if __name__ == "__main__":
    main()
