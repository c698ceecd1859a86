"""An independent evaluation of the CIE 190 tabular UGR that `report ugr-table` computes
(`luxest_photometry::ugr_table`): the same definition, none of luxest's code or numerics.

    python3 pipelines/ugr_table_check.py scenes/photometry/troffer-600-led.ies \
        -o reports/lighting/ugr-table/troffer-600-led.check.csv

The definition (module docs of crates/photometry/src/ugr_table.rs): the standard room X x Y x H
(H = 1: the table does not depend on it), the observer at the middle of the wall of length X,
eyes in the eye plane, looking along Y; luminaires on a 0.25 H grid in the ceiling plane;
endwise = line of sight along the luminaire's C0-C180 axis. L_b = indirect wall illuminance /
pi from ceiling / walls / floor inter-reflection; glare sum with L = I / A_p, omega = A_p / D^2,
Guth's position index (IES Lighting Handbook) capped at 16.

What is computed differently here:
- the photometric file is read by this script's own IES LM-63 / EULUMDAT readers and interpolated
  bilinearly in (C, gamma) by its own code;
- the direct flux on the floor and the walls is integrated over the receiving surfaces (point
  to area, patches of 0.05 H, cosine at the receiver / r^2), not over the luminaire's directions;
- the ceiling-floor form factor is a brute-force patch double sum (0.1 H patches), not the
  closed form.
Only numpy. Writes `x_h,y_h,ceiling,walls,floor,crosswise,endwise` like `report ugr-table -o`.
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOMS = [
    (2, 2),
    (2, 3),
    (2, 4),
    (2, 6),
    (2, 8),
    (2, 12),
    (4, 2),
    (4, 3),
    (4, 4),
    (4, 6),
    (4, 8),
    (4, 12),
    (8, 4),
    (8, 6),
    (8, 8),
    (8, 12),
    (12, 4),
    (12, 6),
    (12, 8),
]
REFL = [(0.7, 0.5, 0.2), (0.7, 0.3, 0.2), (0.5, 0.5, 0.2), (0.5, 0.3, 0.2), (0.3, 0.3, 0.2)]
S = 0.25


class Table:
    """An intensity table over C in [0, 360], gamma in [0, 180] (cd) and a flat opening."""

    def __init__(self, c, g, cd, length, width, round_=False):
        self.c, self.g, self.cd = np.asarray(c, float), np.asarray(g, float), np.asarray(cd, float)
        self.length, self.width = length, width
        # Flat opening area: a rectangle, or a disk / ellipse (IES negative dimensions).
        self.area = length * width * (math.pi / 4 if round_ else 1.0)

    def intensity(self, c, g):
        c = np.mod(c, 360.0)
        i = np.clip(np.searchsorted(self.c, c, side="right") - 1, 0, len(self.c) - 2)
        j = np.clip(np.searchsorted(self.g, g, side="right") - 1, 0, len(self.g) - 2)
        u = (c - self.c[i]) / (self.c[i + 1] - self.c[i])
        v = np.clip((g - self.g[j]) / (self.g[j + 1] - self.g[j]), 0.0, 1.0)
        a = self.cd[i, j] * (1 - v) + self.cd[i, j + 1] * v
        b = self.cd[i + 1, j] * (1 - v) + self.cd[i + 1, j + 1] * v
        return np.where(g <= self.g[-1], a * (1 - u) + b * u, 0.0)


def expand(c_given, g, rows):
    """Full 0..360 C planes from the planes a file gives (by its symmetry)."""
    c_given = list(c_given)
    rows = [list(r) for r in rows]
    last = c_given[-1]
    if len(c_given) == 1:  # rotationally symmetric
        c_full, r_full = [0.0, 360.0], [rows[0], rows[0]]
    else:
        c_full, r_full = list(c_given), list(rows)
        if last == 90.0:  # quadrant: mirror about 90, then about 180
            c_full += [180.0 - x for x in reversed(c_given[:-1])]
            r_full += list(reversed(rows[:-1]))
            last = 180.0
        if last == 180.0:  # half: mirror about 180
            c_full += [360.0 - x for x in reversed(c_full[:-1])]
            r_full += list(reversed(r_full[:-1]))
        elif c_full[-1] < 360.0:
            c_full.append(360.0)
            r_full.append(rows[0])
    return np.array(c_full), np.array(g), np.array(r_full)


def read_ies(path):
    text = Path(path).read_text(errors="replace").splitlines()
    k = next(i for i, line in enumerate(text) if line.startswith("TILT="))
    nums = [float(x) for line in text[k + 1 :] for x in line.split()]
    _n_lamps, _lm, mult, ng, nc, _ptype, units, width, length, _height = nums[:10]
    ballast, _future, _watts = nums[10:13]
    scale = 0.3048 if units == 1 else 1.0
    ng, nc = int(ng), int(nc)
    rest = nums[13:]
    g = rest[:ng]
    c = rest[ng : ng + nc]
    vals = np.array(rest[ng + nc : ng + nc + ng * nc]).reshape(nc, ng) * mult * ballast
    cf, gf, cdf = expand(c, g, vals)
    return Table(cf, gf, cdf, abs(length) * scale, abs(width) * scale, length < 0 and width < 0)


def read_ldt(path):
    t = Path(path).read_text(errors="replace").splitlines()
    isym, mc, _dc, ng = int(t[2]), int(t[3]), float(t[4]), int(t[5])
    n_sets = int(t[25])
    length, width = float(t[15]) / 1000, float(t[16]) / 1000  # luminous area (lines 16, 17), mm
    conv = float(t[23])
    # Lamp data from line 27: per field one line per set (number, type, flux, colour, CRI, W).
    lamp_lm = sum(float(t[26 + 2 * n_sets + s]) for s in range(n_sets))
    base = 26 + 6 * n_sets + 10  # after the lamp sets and the ten direct ratios
    c_all = [float(x) for x in t[base : base + mc]]
    g = [float(x) for x in t[base + mc : base + mc + ng]]
    first = base + mc + ng
    given = {1: 1, 2: mc // 2 + 1, 3: mc // 2 + 1, 4: mc // 4 + 1}.get(isym, mc)
    vals = [float(x) for x in t[first : first + given * ng]]
    rows = np.array(vals).reshape(given, ng) * conv * lamp_lm / 1000.0
    if isym == 1:
        c = [0.0]
    elif isym == 4:
        c = c_all[:given]
    elif isym == 0:
        c = c_all
    else:
        sys.exit(f"{path}: EULUMDAT symmetry {isym} not handled by this check")
    cf, gf, cdf = expand(c, g, rows)
    # EULUMDAT: width 0 means a circular area of diameter `length`.
    return Table(cf, gf, cdf, length, width or length, width == 0)


def position_index(tau, sigma):
    a = (35.2 - 0.31889 * tau - 1.22 * np.exp(-2 * tau / 9)) * 1e-3
    b = (21 + 0.26667 * tau - 0.002963 * tau * tau) * 1e-5
    return np.minimum(np.exp(a * sigma + b * sigma * sigma), 16.0)


def local_angles(d, endwise):
    """(C, gamma) of world directions d (z up) for a luminaire whose C0 axis is world x
    (crosswise) or world y (endwise)."""
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    lx, ly = (y, -x) if endwise else (x, y)
    g = np.degrees(np.arccos(np.clip(-z / np.linalg.norm(d, axis=-1), -1, 1)))
    c = np.degrees(np.arctan2(ly, lx))
    return c, g


def patches(x0, x1, n0, y0, y1, n1):
    a = x0 + (np.arange(n0) + 0.5) * (x1 - x0) / n0
    b = y0 + (np.arange(n1) + 0.5) * (y1 - y0) / n1
    return np.meshgrid(a, b, indexing="ij"), (x1 - x0) * (y1 - y0) / (n0 * n1)


def direct_flux(table, X, Y, endwise, h=0.05):
    lum = np.array([((i + 0.5) * S, (j + 0.5) * S) for i in range(int(X / S)) for j in range(int(Y / S))])
    # Receivers: floor points (normal +z) and wall points (normal inwards), with patch areas.
    (fx, fy), fa = patches(0, X, int(X / h), 0, Y, int(Y / h))
    rec = [np.stack([fx.ravel(), fy.ravel(), np.zeros(fx.size)], 1)]
    nrm = [np.tile([0.0, 0.0, 1.0], (fx.size, 1))]
    area = [np.full(fx.size, fa)]
    for p0, p1, nrm_w, along in [
        ((0, 0), (X, 0), (0, 1, 0), "x"),
        ((0, Y), (X, Y), (0, -1, 0), "x"),
        ((0, 0), (0, Y), (1, 0, 0), "y"),
        ((X, 0), (X, Y), (-1, 0, 0), "y"),
    ]:
        length = X if along == "x" else Y
        (s, z), wa = patches(0, length, int(length / h), 0, 1, int(1 / h))
        s, z = s.ravel(), z.ravel()
        pts = (
            np.stack([p0[0] + s, np.full(s.size, p0[1]), z], 1)
            if along == "x"
            else np.stack([np.full(s.size, p0[0]), p0[1] + s, z], 1)
        )
        rec.append(pts)
        nrm.append(np.tile(nrm_w, (s.size, 1)).astype(float))
        area.append(np.full(s.size, wa))
    sizes = [len(r) for r in rec]
    rec, nrm, area = np.concatenate(rec), np.concatenate(nrm), np.concatenate(area)
    total = np.zeros(len(rec))
    for lx, ly in lum:
        d = rec - np.array([lx, ly, 1.0])
        r2 = np.einsum("ij,ij->i", d, d)
        r = np.sqrt(r2)
        c, g = local_angles(d, endwise)
        cos_r = np.maximum(-np.einsum("ij,ij->i", d, nrm) / r, 0.0)
        total += table.intensity(c, g) * cos_r / r2 * area
    floor = total[: sizes[0]].sum()
    walls = total[sizes[0] :].sum()
    # Upward flux (to the ceiling): the table's integral over gamma > 90 (rarely non-zero).
    gg = np.linspace(90, 180, 181)
    cc = np.linspace(0, 360, 361)
    C, G = np.meshgrid(0.5 * (cc[1:] + cc[:-1]), 0.5 * (gg[1:] + gg[:-1]), indexing="ij")
    w = np.radians(1.0) * (np.cos(np.radians(G - 0.25)) - np.cos(np.radians(G + 0.25)))
    up = (table.intensity(C, G) * w).sum() * len(lum)
    return up, walls, floor


def form_factor_parallel(X, Y, h=0.1):
    (ax, ay), da = patches(0, X, int(X / h), 0, Y, int(Y / h))
    p = np.stack([ax.ravel(), ay.ravel()], 1)
    f = 0.0
    for q in p:
        d2 = ((p - q) ** 2).sum(1) + 1.0
        f += (1.0 / (math.pi * d2 * d2)).sum() * da * da
    return f / (X * Y)


def tabular(table, X, Y, refl, endwise, flux, ff):
    ac, aw = X * Y, 2 * (X + Y)
    fcw = 1 - ff
    fwc = ac * fcw / aw
    F = np.array([[0, fcw, ff], [fwc, 1 - 2 * fwc, fwc], [ff, fcw, 0]])
    e = np.array(flux) / np.array([ac, aw, ac])
    rho = np.array(refl)
    m = np.linalg.solve(np.eye(3) - rho[:, None] * F, rho * e)
    lb = F[1] @ m / math.pi
    eye = np.array([X / 2, 0.0, 0.0])
    lum = np.array([((i + 0.5) * S, (j + 0.5) * S, 1.0) for i in range(int(X / S)) for j in range(int(Y / S))])
    d = lum - eye
    dist = np.linalg.norm(d, axis=1)
    sigma = np.degrees(np.arccos(d[:, 1] / dist))
    tau = np.degrees(np.arctan2(np.abs(d[:, 0]), d[:, 2]))
    c, g = local_angles(-d, endwise)
    ap = table.area * np.cos(np.radians(g))
    lumi = table.intensity(c, g) / ap
    omega = ap / dist**2
    p = position_index(tau, sigma)
    s = (lumi**2 * omega / p**2)[sigma < 90].sum()
    return 8 * math.log10(0.25 / lb * s)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("file")
    ap.add_argument("-o", "--out", required=True)
    a = ap.parse_args()
    table = read_ies(a.file) if a.file.lower().endswith(".ies") else read_ldt(a.file)
    rows = []
    for X, Y in ROOMS:
        ff = form_factor_parallel(X, Y)
        fl = {e: direct_flux(table, X, Y, e) for e in (False, True)}
        for r in REFL:
            cw = tabular(table, X, Y, r, False, fl[False], ff)
            ew = tabular(table, X, Y, r, True, fl[True], ff)
            rows.append(f"{X},{Y},{r[0]},{r[1]},{r[2]},{cw:.3f},{ew:.3f}")
        print(f"{X}H x {Y}H: crosswise {rows[-5].split(',')[5]} endwise {rows[-5].split(',')[6]}", file=sys.stderr)
    Path(a.out).write_text(
        f"# independent tabular UGR of {a.file} (pipelines/ugr_table_check.py)\n"
        "x_h,y_h,ceiling,walls,floor,crosswise,endwise\n" + "\n".join(rows) + "\n"
    )


if __name__ == "__main__":
    main()
