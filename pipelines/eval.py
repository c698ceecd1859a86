#!/usr/bin/env python3
"""`make eval`'s summary: reports/summary.md with tables and plots (reports/plots/*.png) drawn
from the CSV/RON reports of the `evaluate` stage that the rules of pipelines/eval.mk write
(every stage run is a Make rule; this file only reads reports and draws).

  eval.py summary --reports reports --cornell CSV [--cornell-own-features CSV] --dataset CSV...
                  [--public CSV... --flip-dir DIR] --sensors CSV... [values of
                  pipelines/presets.mk: --preset --model --ref-spp --ref-seed --noisy-seed
                  --dataset-ref-spp --public-ref-spp --sensor-scale]

1. Cornell box (256 x 256): error vs wall-clock time and vs samples for path tracing, + denoise,
   double local estimate, + denoise, and the Pareto front over all of them.
2. The held-out test scenes of the dataset: the same, means over the scenes.
2b. The public interiors held out (scenes/public/): luxest's denoiser against Intel Open Image
   Denoise 1.4.3 and 2.5.1 with antialiased features and with those of each snapshot's own samples, PSNR, SSIM,
   FLIP, FLIP on textured regions (texture_mask), colour shift, inference CPU seconds per
   megapixel, and the double-local-estimate images.
3. The seed's experiment done right: PSNR/SSIM/FLIP of the noisy and the denoised progressive
   snapshots against the converged reference over time, and the time at which each reaches
   SSIM 0.95 and 0.98.
4. Sensor results of the local estimate against exact solutions (the cases of `make validate`).

Times are wall-clock seconds recorded in the images' headers: render (trace/estimate) +
features (aov-write) + inference (denoise), excluding file I/O and process start."""

import argparse
import functools
import math
import os
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
import luxest_contract as contract  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

THRESHOLDS = (0.95, 0.98)
METRICS = [("rel_mse", "relMSE (linear)"), ("one_minus_ssim", "1 - SSIM (tonemapped)"), ("flip", "FLIP (LDR)")]
PT, DLE, LT = contract.PATH_TRACING, contract.DOUBLE_LOCAL_ESTIMATE, contract.LIGHT_TRACING
DENOISED, OIDN, OIDN2 = contract.DENOISED_SUFFIX, contract.OIDN_SUFFIX, contract.OIDN2_SUFFIX
PEER_NAMES = {OIDN: "OIDN 1.4.3", OIDN2: "OIDN 2.5.1"}
# The textured regions of an image (texture_mask): pixels whose albedo luminance varies, over the
# (2 TEXTURE_RADIUS + 1)² window around them, with a standard deviation of at least
# TEXTURE_STD (albedo units: texture detail and object edges; flat-coloured walls are out).
TEXTURE_RADIUS = 3
TEXTURE_STD = 0.02
STYLE = {
    PT: ("tab:blue", "o"),
    PT + DENOISED: ("tab:orange", "s"),
    DLE: ("tab:green", "^"),
    DLE + DENOISED: ("tab:red", "D"),
    LT: ("tab:purple", "v"),
    PT + OIDN: ("tab:gray", "P"),
    DLE + OIDN: ("tab:brown", "X"),
    PT + OIDN2: ("tab:olive", "p"),
    DLE + OIDN2: ("tab:cyan", "x"),
}


def read_csv(path):
    """`evaluate images`' report, with 1 − SSIM added."""
    rows = contract.read_image_report(path)
    for r in rows:
        r["one_minus_ssim"] = 1.0 - r["ssim"]
    return rows


def pareto(points):
    """Points (time, error, label) not dominated by a faster-and-better one, by time."""
    front, best = [], float("inf")
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def front_text(front):
    """A Pareto front as runs of one estimator: `path-tracing 64–1024 (3.2–48 s)`."""
    groups = []
    for t, _, label in front:
        est, n = label.rsplit(" ", 1)
        if groups and groups[-1][0] == est:
            groups[-1][1].append((n, t))
        else:
            groups.append((est, [(n, t)]))
    parts = []
    for est, pts in groups:
        (n0, t0), (n1, t1) = pts[0], pts[-1]
        parts.append(f"{est} {n0} ({t0:.2g} s)" if len(pts) == 1 else f"{est} {n0}–{n1} ({t0:.2g}–{t1:.2g} s)")
    return " → ".join(parts)


def crossing_time(rows, threshold):
    """First time SSIM >= threshold, interpolated in log time between snapshots; None if never."""
    rows = sorted(rows, key=lambda r: r["total_seconds"])
    prev = None
    for r in rows:
        if r["ssim"] >= threshold:
            if prev is None:
                return r["total_seconds"], False
            t0, t1, s0, s1 = prev["total_seconds"], r["total_seconds"], prev["ssim"], r["ssim"]
            f = (threshold - s0) / (s1 - s0)
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0))), False
        prev = r
    return None


def extrapolated_time(rows, threshold):
    """Time at which 1 - SSIM would reach 1 - threshold on a power law fitted to the last 4
    snapshots (for a noisy run that does not get there); None if the fit does not decrease."""
    pts = sorted(rows, key=lambda r: r["total_seconds"])[-4:]
    xs = [math.log(r["total_seconds"]) for r in pts]
    ys = [math.log(max(1.0 - r["ssim"], 1e-12)) for r in pts]
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    if sxx == 0:
        return None
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
    if slope > -0.1:
        return None  # a plateau: the run is not converging towards the reference
    t = math.exp(mx + (math.log(1.0 - threshold) - my) / slope)
    return (t, slope) if t < 100 * pts[-1]["total_seconds"] else None


def plot_trade(rows, title, path, x_key="total_seconds", x_label="wall-clock seconds (render + features + denoise)"):
    fig, axes = plt.subplots(1, len(METRICS), figsize=(5.2 * len(METRICS), 4.2))
    for ax, (key, label) in zip(axes, METRICS):
        for est, (color, marker) in STYLE.items():
            pts = sorted([(r[x_key], r[key]) for r in rows if r["estimator"] == est and r[key] > 0], key=lambda p: p[0])
            if pts:
                ax.plot(*zip(*pts), marker=marker, color=color, label=est, lw=1.2, ms=4)
        if x_key == "total_seconds":
            front = pareto([(r[x_key], r[key], r["estimator"]) for r in rows if r[key] > 0])
            if front:
                ax.step(
                    [p[0] for p in front],
                    [p[1] for p in front],
                    where="post",
                    color="k",
                    lw=2,
                    alpha=0.35,
                    label="Pareto front",
                )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(x_label)
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_progressive(noisy, denoised, path):
    fig, axes = plt.subplots(1, 3, figsize=(15.6, 4.2))
    for ax, (key, label) in zip(
        axes, [("psnr_db", "PSNR dB (tonemapped)"), ("ssim", "SSIM (tonemapped)"), ("flip", "FLIP (LDR)")]
    ):
        for rows, name, color in [(noisy, "noisy", "tab:blue"), (denoised, "denoised", "tab:orange")]:
            pts = sorted((r["total_seconds"], r[key]) for r in rows)
            ax.plot(*zip(*pts), marker="o", ms=3, color=color, label=name)
        if key == "ssim":
            for t in THRESHOLDS:
                ax.axhline(t, color="gray", ls="--", lw=0.8)
        ax.set_xscale("log")
        ax.set_xlabel("wall-clock seconds")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend()
    fig.suptitle("Progressive Cornell box vs the converged reference")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fmt_time(t):
    return "—" if t is None else f"{t:.2f} s"


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def sensor_row(csv_path):
    """The summary row of one `evaluate sensors` CSV report: case, kind, points, paths, seconds
    (from the results' run metadata), max |z|, mean z², RMS relative error."""
    rows, _ = contract.read_sensor_report(csv_path)
    zs = [r["z"] for r in rows]
    rel = [r["relative_error"] for r in rows]
    run = contract.read_sensor_run(rows[0]["results"])
    name = Path(csv_path).name[len("sensors-") : -len(".csv")]
    return [
        name,
        rows[0]["case"].split(":")[0],
        len(rows),
        run["samples"],
        f"{run['seconds']:.2f}",
        f"{max(abs(z) for z in zs):.2f}",
        f"{sum(z * z for z in zs) / len(zs):.2f}",
        f"{math.sqrt(sum(e * e for e in rel) / len(rel)):.2e}",
    ]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    c = sub.add_parser("summary")
    c.add_argument("--reports", required=True)
    c.add_argument("--cornell", required=True)
    c.add_argument("--cornell-own-features", help="the Cornell report with the features of each snapshot's own samples")
    c.add_argument("--dataset", nargs="*", default=[])
    c.add_argument("--public", nargs="*", default=[], help="public-<name>[-own-features].images.csv reports")
    c.add_argument("--flip-dir", help="the FLIP maps' directory (a subdirectory per public report)")
    c.add_argument("--public-ref-spp", type=int)
    c.add_argument("--sensors", nargs="*", default=[])
    c.add_argument("--preset", required=True)
    c.add_argument("--model", required=True)
    c.add_argument("--ref-spp", type=int, required=True)
    c.add_argument("--ref-seed", type=int, required=True)
    c.add_argument("--noisy-seed", type=int, required=True)
    c.add_argument("--dataset-ref-spp", type=int, required=True)
    c.add_argument("--sensor-scale", type=float, required=True)
    args = ap.parse_args(argv)
    reports = Path(args.reports)
    plots = reports / "plots"
    plots.mkdir(parents=True, exist_ok=True)
    cb_rows = read_csv(args.cornell)
    ds_rows, ds_names = [], []
    for f in sorted(args.dataset):
        name = Path(f).name[len("dataset-") : -len(".images.csv")]
        for r in read_csv(f):
            r["scene"] = name
            ds_rows.append(r)
        ds_names.append(name)
    sensor_rows = [sensor_row(f) for f in args.sensors]
    cb_df_rows = read_csv(args.cornell_own_features) if args.cornell_own_features else []
    public = read_public(args.public, args.flip_dir)
    for rows in [cb_rows, cb_df_rows, ds_rows] + [rows for by in public.values() for rows in by.values()]:
        check_seeds(rows)
    write_summary(args, reports, plots, cb_rows, ds_rows, ds_names, sensor_rows, Path(args.model), cb_df_rows, public)


def read_public(paths, flip_dir):
    """The public interiors' reports: {scene: {"antialiased" | "own": rows}}, each row with its
    FLIP on textured regions (`flip_textured`, None without a map or an albedo)."""
    out = {}
    for f in sorted(paths):
        stem = Path(f).name[: -len(".images.csv")]
        name = stem[len("public-") :]
        features = "antialiased"
        if name.endswith("-own-features"):
            name, features = name[: -len("-own-features")], "own"
        rows = read_csv(f)
        for r in rows:
            r["scene"] = name
            r["flip_textured"] = textured_flip(r["image"], r["reference"], Path(flip_dir) / stem) if flip_dir else None
        out.setdefault(name, {})[features] = rows
    return out


def texture_mask(albedo):
    """The textured regions of an image from its albedo (H, W, 3): True where the albedo's
    luminance has a standard deviation of at least TEXTURE_STD over the (2 TEXTURE_RADIUS + 1)²
    window around the pixel (the window clipped at the border). The one definition of the
    summary's FLIP on textured regions."""
    import numpy as np

    y = np.asarray(albedo, np.float64) @ np.array([0.2126, 0.7152, 0.0722])

    def box(a):  # window sums by summed-area tables, clipped at the border
        p = np.pad(a, ((1, 0), (1, 0))).cumsum(0).cumsum(1)
        h, w = a.shape
        i0 = np.clip(np.arange(h) - TEXTURE_RADIUS, 0, h)
        i1 = np.clip(np.arange(h) + TEXTURE_RADIUS + 1, 0, h)
        j0 = np.clip(np.arange(w) - TEXTURE_RADIUS, 0, w)
        j1 = np.clip(np.arange(w) + TEXTURE_RADIUS + 1, 0, w)
        return p[i1][:, j1] - p[i0][:, j1] - p[i1][:, j0] + p[i0][:, j0]

    n = box(np.ones_like(y))
    mean = box(y) / n
    var = np.maximum(box(y * y) / n - mean * mean, 0.0)
    return var >= TEXTURE_STD**2


@functools.lru_cache(maxsize=None)
def _mask(albedo_path):
    return texture_mask(contract.read(albedo_path).pixels)


def textured_flip(image, reference, flip_dir):
    """Mean of an image's FLIP map (`evaluate images --flip-maps`: <flip_dir>/<image name
    without .exr>.flip.exr) over the texture mask of the reference's albedo (`<ref>_ref.alb.exr`
    beside the reference, aov-write --reference); None when either file is missing or the mask
    is empty."""
    parsed = contract.parse_image_name(Path(reference).name)
    if parsed is None:
        return None
    albedo = Path(reference).with_name(contract.image_name(parsed.name, "alb", None))
    flip = Path(flip_dir) / (Path(image).name[: -len(".exr")] + ".flip.exr")
    if not (albedo.exists() and flip.exists()):
        return None
    mask = _mask(str(albedo))
    if not mask.any():
        return None
    return float(contract.read(flip).pixels[..., 0].astype("float64")[mask].mean())


@functools.lru_cache(maxsize=None)
def _seed(path):
    return contract.read(path).value(contract.SEED) if Path(path).exists() else None


def check_seeds(rows):
    """Exit with one line if a scored image shares its reference's seed (luxest.seed): its
    samples would be the reference's own, and the error it is scored with too small."""
    for r in rows:
        if "image" not in r:
            continue
        ref, img = _seed(r["reference"]), _seed(r["image"])
        if ref is not None and ref == img:
            raise SystemExit(f"eval: {r['image']}: rendered with its reference's seed {ref} ({r['reference']})")


def level_key(r):
    return (r["estimator"], int(r["samples"]))


@functools.lru_cache(maxsize=None)
def _image_facts(path):
    """What the summary takes from one image file, read once (every row of a report shares its
    reference, and a denoised image gives both its colour shift and its costs): the linear mean
    of each channel and the (wall-clock, CPU) inference seconds per megapixel its header records
    (`luxest.denoiseSeconds`, `luxest.denoiseCpuSeconds`; None where absent)."""
    img = contract.read(path)
    mp = img.pixels.shape[0] * img.pixels.shape[1] / 1e6
    costs = tuple(
        None if v is None else v / mp
        for v in (img.value(contract.DENOISE_SECONDS), img.value(contract.DENOISE_CPU_SECONDS))
    )
    return img.pixels.reshape(-1, 3).astype("float64").mean(0), costs


def channel_means(path):
    """The linear mean of each channel of an image."""
    return _image_facts(str(path))[0]


def colour_shift(image, reference):
    """max over R, G, B of |mean of the image's channel / mean of the reference's − 1| (linear
    values, whole image): the issue-11 check that a denoiser shifts no colour. None when a file
    is missing (summaries of reports whose images were deleted)."""
    if not (Path(image).exists() and Path(reference).exists()):
        return None
    a, b = channel_means(image), channel_means(reference)
    shifts = [abs(a[c] / b[c] - 1.0) for c in range(3) if b[c] > 0]
    return float(max(shifts)) if shifts else None


def row_colour_shift(r):
    """A report row's colour shift: stored (a mean over scenes), else from its image files."""
    if "colour_shift" in r:
        return r["colour_shift"]
    return colour_shift(r["image"], r["reference"]) if "image" in r else None


def denoise_costs(image):
    """(wall-clock, CPU) inference seconds per megapixel a denoised image records; None for what
    is missing (a deleted file; a denoiser swapped in through DENOISE may record no CPU
    seconds)."""
    return _image_facts(str(image))[1] if Path(image).exists() else (None, None)


def row_denoise_costs(r):
    """A report row's denoise_costs: stored (a mean over scenes), else from its image file."""
    if "denoise_costs" in r:
        return r["denoise_costs"]
    return denoise_costs(r["image"]) if "image" in r else (None, None)


def mean_or_none(values):
    values = list(values)
    return None if not values or None in values else sum(values) / len(values)


def _pct(v):
    return "—" if v is None else f"{100 * v:.2f} %"


def peer_table(rows, what):
    """luxest's denoiser against Intel Open Image Denoise (the `+oidn` rows, and `+oidn2` where
    there are any) on the same inputs: PSNR / SSIM / FLIP per input level, and the inference time
    per megapixel of each, wall-clock and CPU seconds (excluding I/O, the run's threads)."""
    by = {(r["estimator"], int(r["samples"])): r for r in rows}
    out = []
    for base in (PT, DLE):
        peers = [p for p in (OIDN, OIDN2) if any(e == base + p for e, _ in by)]
        levels = sorted(
            n for (e, n) in by if e == base + DENOISED and (base, n) in by and any((base + p, n) in by for p in peers)
        )
        if not levels:
            continue
        trs = []
        for n in levels:
            a, d = by[(base, n)], by[(base + DENOISED, n)]
            ps = [by.get((base + p, n)) for p in peers]
            cell = lambda r, k, f: "—" if r is None else f"{r[k]:{f}}"
            trs.append(
                [n]
                + [
                    " / ".join(cell(r, k, f) for r in [a, d] + ps)
                    for k, f in (("psnr_db", ".2f"), ("ssim", ".4f"), ("flip", ".4f"))
                ]
                + [
                    " / ".join(
                        "—" if v is None else f"{scale * v:{f}}"
                        for v in [row_denoise_costs(r)[j] if r is not None else None for r in [d] + ps]
                    )
                    for j, scale, f in ((0, 1e3, ".0f"), (1, 1.0, ".2f"))
                ]
                + [" / ".join("—" if r is None else _pct(row_colour_shift(r)) for r in [a, d] + ps)]
            )
        unit = "spp" if base == PT else "paths"
        names = " / ".join(PEER_NAMES[p] for p in peers)
        out += [
            f"### {base}: luxest's denoiser against Intel Open Image Denoise {names.replace('OIDN ', '')} ({what})",
            "",
            f"Each cell: noisy / luxest (`denoise`) / {names} (hdr + albedo + normal, pipelines/oidn_denoise.py"
            + (", 2.5.1 at quality high" if OIDN2 in peers else "")
            + "), the same inputs and features.",
            "",
            table(
                [
                    unit,
                    "PSNR dB",
                    "SSIM",
                    "FLIP",
                    f"inference ms per megapixel (luxest / {names})",
                    f"inference CPU-s per megapixel (luxest / {names})",
                    "colour shift: max over R, G, B of abs(mean / reference mean − 1)"
                    + (" (mean over scenes)" if "colour_shift" in rows[0] else ""),
                ],
                trs,
            ),
            "",
        ]
    return out


def paired_gaps(rows, base, key="psnr_db", peer=OIDN):
    """Scene by scene, luxest's denoised `key` minus the peer's on the same input (`<base>+denoise`
    against `<base><peer>` rows with a `scene`; peer `+oidn` or `+oidn2`), per level in increasing
    order: [(level, {scene: difference}, [scenes scored by one of the two only, or with a
    non-finite difference])]."""
    by = {}
    for r in rows:
        if r["estimator"] in (base + DENOISED, base + peer):
            one = by.setdefault(int(r["samples"]), {}).setdefault(r["scene"], {})
            if r["estimator"] in one:
                raise SystemExit(f"eval: scene {r['scene']}: two {r['estimator']} rows at {int(r['samples'])}")
            one[r["estimator"]] = r[key]
    out = []
    for n, scenes in sorted(by.items()):
        diffs = {s: v[base + DENOISED] - v[base + peer] for s, v in sorted(scenes.items()) if len(v) == 2}
        diffs = {s: d for s, d in diffs.items() if math.isfinite(d)}
        if diffs:
            out.append((n, diffs, sorted(set(scenes) - set(diffs))))
    return out


def gap_stats(diffs):
    """(mean, standard error of the mean, min, max, count > 0) of per-scene differences; the
    standard error (sample standard deviation / sqrt(n)) is None for one scene."""
    v = list(diffs)
    mean = sum(v) / len(v)
    se = math.sqrt(sum((x - mean) ** 2 for x in v) / (len(v) - 1) / len(v)) if len(v) > 1 else None
    return mean, se, min(v), max(v), sum(x > 0 for x in v)


def gap_table(rows, names, peer=None):
    """The held-out bar (luxest ≥ OIDN + 1 dB in mean PSNR at every level), scene by
    scene: the mean difference with its standard error over the scenes, its range, the scenes
    where luxest is ahead, and each scene's difference when there are few; a level where a scene
    lacks one of the two is scored over the others and says which. Against OIDN 2.5.1 where
    `rows` have its images (peer None), else 1.4.3."""
    out, few = [], len(names) <= 6
    if peer is None:
        peer = OIDN2 if any(r["estimator"].endswith(OIDN2) for r in rows) else OIDN
    for base, unit in ((PT, "spp"), (DLE, "paths")):
        gaps = paired_gaps(rows, base, peer=peer)
        if not gaps:
            continue
        trs, notes = [], []
        for n, d, missing in gaps:
            mean, se, lo, hi, ahead = gap_stats(d.values())
            trs.append(
                [
                    n,
                    f"{mean:+.2f}" + ("" if se is None else f" ± {se:.2f}"),
                    f"{lo:+.2f} … {hi:+.2f}",
                    f"{ahead} of {len(d)}",
                    "yes" if mean >= 1.0 else "no",
                ]
                + ([" / ".join(f"{d[s]:+.2f}" if s in d else "—" for s in names)] if few else [])
            )
            if missing:
                notes.append(f"- {n} {unit}: without {', '.join(missing)} (scored by one denoiser only, or not finite)")
        out += [
            f"### {base}: luxest − {PEER_NAMES[peer] if peer == OIDN2 else 'OIDN'} in PSNR dB, scene by scene (held-out scenes)",
            "",
            "The mean difference ± its standard error over the scenes (sample standard deviation / √n): how far the "
            "held-out bar's mean would move with other scenes of the same kind.",
            "",
            table(
                [unit, "mean ± s.e.", "range", "luxest ahead", "mean ≥ +1 dB"] + ([" / ".join(names)] if few else []),
                trs,
            ),
            "",
        ] + (notes + [""] if notes else [])
    return out


def _by(rows):
    return {(r["estimator"], int(r["samples"])): r for r in rows}


def _yes(ok):
    return "yes" if ok else "**no**"


def cornell_bar(aa_rows, df_rows, levels=(1, 4, 16, 64)):
    """Issue 52's Cornell-box bar, per features kind and level: luxest ≥ OIDN 2.5.1 in PSNR,
    SSIM and FLIP (lower FLIP is better), colour shift within 1 %, and never worse than its
    input (PSNR) at any level."""
    out = []
    for kind, rows in (("antialiased", aa_rows), ("own-sample", df_rows)):
        by = _by(rows)
        trs = []
        for n in sorted({int(r["samples"]) for r in rows if r["estimator"] == PT + DENOISED}):
            d, o, a = by.get((PT + DENOISED, n)), by.get((PT + OIDN2, n)), by.get((PT, n))
            if d is None or a is None:
                continue
            shift = row_colour_shift(d)
            cells = [n, _yes(d["psnr_db"] >= a["psnr_db"]), "—" if shift is None else _yes(shift <= 0.01)]
            if o is not None and n in levels:
                cells += [
                    f"{d['psnr_db'] - o['psnr_db']:+.2f} {_yes(d['psnr_db'] >= o['psnr_db'])}",
                    f"{d['ssim'] - o['ssim']:+.4f} {_yes(d['ssim'] >= o['ssim'])}",
                    f"{d['flip'] - o['flip']:+.4f} {_yes(d['flip'] <= o['flip'])}",
                ]
            else:
                cells += ["", "", ""]
            trs.append(cells)
        if trs:
            out += [
                f"Features {kind}:",
                "",
                table(
                    [
                        "spp",
                        "luxest ≥ noisy (PSNR)",
                        "colour shift ≤ 1 %",
                        "PSNR luxest − OIDN 2.5.1",
                        "SSIM luxest − OIDN 2.5.1",
                        "FLIP luxest − OIDN 2.5.1 (≤ 0 is ahead)",
                    ],
                    trs,
                ),
                "",
            ]
    return out


def public_section(public, ref_spp):
    """The public interiors: per scene and features kind, the peer table (noisy / luxest / OIDN
    1.4.3 / OIDN 2.5.1), FLIP on textured regions, and issue 52's bar over the interiors' means."""
    if not public:
        return []
    names = sorted(public)
    out = [
        f"## Public interiors held out ({', '.join(names)})",
        "",
        "Scenes no one here wrote (scenes/public/, CC-BY, credited in scenes/public/README.md; never in training), "
        f"imported by `scene-compile`, path-traced by `trace`: references of {ref_spp} spp with their own seed, one "
        "progressive run with the noisy seed, its features antialiased (`aov-write --min-samples`) and of each "
        "snapshot's own samples (`--min-samples 1`); double-local-estimate images denoised with the last snapshot's "
        "antialiased features. OIDN 2.5.1 runs at quality high, antialiased features as clean (cleanAux), own-sample "
        "ones prefiltered by its own filters (pipelines/oidn_denoise.py). FLIP on textured regions: the mean of the "
        f"FLIP map where the reference albedo's luminance has a standard deviation ≥ {TEXTURE_STD} over a "
        f"{2 * TEXTURE_RADIUS + 1}² window (pipelines/eval.py `texture_mask`).",
        "",
    ]
    for name in names:
        for kind in ("antialiased", "own"):
            rows = public[name].get(kind)
            if not rows:
                continue
            what = f"{name}, {'antialiased' if kind == 'antialiased' else 'own-sample'} features"
            out += peer_table(rows, what)
            by = _by(rows)
            trs = []
            for n in sorted({int(r["samples"]) for r in rows if r["estimator"] == PT}):
                cells = [by.get((e, n)) for e in (PT, PT + DENOISED, PT + OIDN, PT + OIDN2)]
                if any(c is not None and c.get("flip_textured") is not None for c in cells):
                    trs.append(
                        [n]
                        + [
                            " / ".join(
                                "—" if c is None or c.get("flip_textured") is None else f"{c['flip_textured']:.4f}"
                                for c in cells
                            )
                        ]
                    )
            if trs:
                frac = _mask_fraction(rows)
                out += [
                    f"FLIP on textured regions ({what}; "
                    + ("" if frac is None else f"{100 * frac:.0f} % of the pixels; ")
                    + "noisy / luxest / OIDN 1.4.3 / OIDN 2.5.1):",
                    "",
                    table(["spp", "FLIP, textured regions"], trs),
                    "",
                ]
    # The bar: means over the interiors, luxest − OIDN 2.5.1.
    trs = []
    for kind, tol in (("antialiased", 0.0), ("own", -0.5)):
        per = [public[n][kind] for n in names if kind in public[n]]
        if len(per) != len(names):
            continue
        for base in (PT, DLE):
            levels = sorted(
                set.intersection(
                    *[{int(r["samples"]) for r in rows if r["estimator"] == base + DENOISED} for rows in per]
                )
            )
            for n in levels:
                rs = [_by(rows) for rows in per]
                if not all((base + OIDN2, n) in b and (base, n) in b for b in rs):
                    continue
                mean = lambda e, k: sum(b[(e, n)][k] for b in rs) / len(rs)
                dp = mean(base + DENOISED, "psnr_db") - mean(base + OIDN2, "psnr_db")
                df = mean(base + DENOISED, "flip") - mean(base + OIDN2, "flip")
                tex = [
                    (b[(base + DENOISED, n)].get("flip_textured"), b[(base + OIDN2, n)].get("flip_textured"))
                    for b in rs
                ]
                dt = None if any(t is None for p in tex for t in p) else sum(a - o for a, o in tex) / len(tex)
                gain = mean(base + DENOISED, "psnr_db") - mean(base, "psnr_db")
                trs.append(
                    [
                        "antialiased" if kind == "antialiased" else "own",
                        base,
                        n,
                        f"{dp:+.2f} {_yes(dp >= tol)}",
                        f"{df:+.4f} {_yes(df <= 0)}" if kind == "antialiased" else f"{df:+.4f}",
                        "—" if dt is None else f"{dt:+.4f} {_yes(dt <= 0)}",
                        f"{gain:+.2f}",
                    ]
                )
    if trs:
        out += [
            "### Issue 52's bar on the public interiors: luxest − OIDN 2.5.1, means over the interiors",
            "",
            "PSNR: ≥ 0 with antialiased features, ≥ −0.5 dB with own-sample ones; FLIP (lower is better): ≤ 0 with "
            "antialiased features; FLIP on textured regions ≤ 0; the denoiser's gain over its input in PSNR.",
            "",
            table(
                [
                    "features",
                    "estimator",
                    "spp / paths",
                    "PSNR dB",
                    "FLIP",
                    "FLIP, textured regions",
                    "luxest − noisy, PSNR dB",
                ],
                trs,
            ),
            "",
        ]
    return out


def _mask_fraction(rows):
    """The fraction of pixels in the texture mask of a report's reference albedo, None without
    it."""
    ref = rows[0]["reference"]
    parsed = contract.parse_image_name(Path(ref).name)
    if parsed is None:
        return None
    albedo = Path(ref).with_name(contract.image_name(parsed.name, "alb", None))
    return float(_mask(str(albedo)).mean()) if albedo.exists() else None


def write_summary(args, reports, plots, cb_rows, ds_rows, ds_names, sensor_rows, model, cb_df_rows=(), public=None):
    plot_trade(cb_rows, "Cornell box 256² — error vs time", plots / "cornell-box-time.png")
    plot_trade(
        cb_rows,
        "Cornell box 256² — error vs samples (spp or light paths)",
        plots / "cornell-box-samples.png",
        x_key="samples",
        x_label="samples per pixel (PT) / light paths (DLE)",
    )
    # Dataset: mean over scenes per estimator and level (relMSE, FLIP, 1-SSIM arithmetic means).
    agg = {}
    for r in ds_rows:
        agg.setdefault(level_key(r), []).append(r)
    ds_mean = []
    for (est, n), rs in sorted(agg.items()):
        m = {"estimator": est, "samples": n, "scenes": len(rs)}
        for k in ("total_seconds", "psnr_db", "ssim", "flip", "rel_mse", "smape", "one_minus_ssim"):
            m[k] = sum(r[k] for r in rs) / len(rs)
        m["colour_shift"] = mean_or_none(row_colour_shift(r) for r in rs)
        costs = [row_denoise_costs(r) for r in rs]
        m["denoise_costs"] = tuple(mean_or_none(c[j] for c in costs) for j in (0, 1))
        ds_mean.append(m)
    if ds_mean:
        plot_trade(ds_mean, f"Held-out test scenes ({len(ds_names)}), mean — error vs time", plots / "dataset-time.png")
        plot_trade(
            ds_mean,
            f"Held-out test scenes ({len(ds_names)}), mean — error vs samples",
            plots / "dataset-samples.png",
            x_key="samples",
            x_label="samples per pixel (PT) / light paths (DLE)",
        )
    noisy = [r for r in cb_rows if r["estimator"] == PT]
    den = [r for r in cb_rows if r["estimator"] == PT + DENOISED]
    plot_progressive(noisy, den, plots / "cornell-box-progressive.png")

    lines = [
        f"# luxest evaluation summary ({args.preset})",
        "",
        f"Written by `make eval` (pipelines/eval.mk; this summary by pipelines/eval.py) on this machine "
        f"({os.cpu_count()} cores). Denoiser: `{model.relative_to(ROOT) if model.is_absolute() and ROOT in model.parents else model}`.",
        "",
        "Metrics (crates/evaluate, each checked against an established implementation to 1e-4): PSNR, SSIM, "
        "MS-SSIM and FLIP on tonemapped images — per channel `x = max(v, 0)·k` with `k` the reference's autoexposure "
        "`0.18 / exp(mean ln(Y + 1e-4))`, Reinhard `x / (1 + x)`, sRGB OETF, clamped to [0, 1]; FLIP is LDR-FLIP at "
        "67 pixels per degree; relMSE `mean (t - r)² / (r² + 0.01)` and SMAPE `mean |t - r| / (|t| + |r| + 0.01)` on "
        "linear values. Times are wall-clock seconds: render + albedo/normal features + inference, excluding I/O.",
        "",
    ]

    # Cornell trade table.
    lines += [
        "## Cornell box: the speed/accuracy trade",
        "",
        f"Reference: {args.ref_spp} spp path tracing (seed {args.ref_seed}, independent of the runs scored). Path tracing "
        f"is one progressive run (seed {args.noisy_seed}) whose snapshots are denoised with the albedo/normal features of the same snapshot; "
        "double-local-estimate (DLE) images (one camera sample per pixel) are denoised with the 64-spp features.",
        "",
    ]
    show = [
        r
        for r in cb_rows
        if r["estimator"].startswith((DLE, LT)) or int(r["samples"]) in (1, 4, 16, 64, 256, 1024, 4096)
    ]
    rows = [
        [
            r["estimator"],
            int(r["samples"]),
            f"{r['total_seconds']:.2f}",
            f"{r['psnr_db']:.2f}",
            f"{r['ssim']:.4f}",
            "" if math.isnan(r["ms_ssim"]) else f"{r['ms_ssim']:.4f}",
            f"{r['flip']:.4f}",
            f"{r['rel_mse']:.3e}",
            f"{r['smape']:.4f}",
        ]
        for r in sorted(show, key=lambda r: (r["estimator"], r["samples"]))
    ]
    lines += [
        table(["estimator", "spp / paths", "seconds", "PSNR dB", "SSIM", "MS-SSIM", "FLIP", "relMSE", "SMAPE"], rows),
        "",
    ]
    for key, label in METRICS:
        front = pareto([(r["total_seconds"], r[key], f"{r['estimator']} {int(r['samples'])}") for r in cb_rows])
        lines.append(f"- Pareto front in {label}: " + front_text(front))
    lines += [
        "",
        "![error vs time](plots/cornell-box-time.png)",
        "",
        "![error vs samples](plots/cornell-box-samples.png)",
        "",
    ]

    lines += peer_table(cb_rows, "Cornell box 256², antialiased features")
    if cb_df_rows:
        lines += peer_table(cb_df_rows, "Cornell box 256², features of each snapshot's own samples")
    if any(r["estimator"] == PT + OIDN2 for r in cb_rows):
        lines += [
            "### Issue 52's bar on the Cornell box: luxest against OIDN 2.5.1",
            "",
        ] + cornell_bar(cb_rows, list(cb_df_rows))

    # Progressive experiment.
    lines += [
        "## The progressive experiment (the thesis' Fig. done against a converged reference)",
        "",
        "Each snapshot of the progressive path-traced run, noisy and denoised, is scored against the converged reference "
        "(the thesis scored denoised against noisy, which measures nothing about correctness).",
        "",
    ]
    trow = []
    for t in THRESHOLDS:
        row = [f"SSIM ≥ {t}"]
        for rows_ in (noisy, den):
            c = crossing_time(rows_, t)
            if c is not None:
                spp = min((r for r in rows_ if r["ssim"] >= t), key=lambda r: r["total_seconds"])["samples"]
                row.append(f"{c[0]:.2f} s (first snapshot: {int(spp)} spp)")
            else:
                e = extrapolated_time(rows_, t)
                best = max(r["ssim"] for r in rows_)
                last = max(rows_, key=lambda r: r["total_seconds"])
                row.append(
                    f"not reached in {last['total_seconds']:.0f} s (best {best:.4f})"
                    + (f"; power-law extrapolation of 1 − SSIM: ≈ {e[0]:.0f} s" if e else "; no longer improving")
                )
        trow.append(row)
    lines += [table(["threshold", "noisy path tracing", "denoised path tracing"], trow), ""]
    prow = []
    for rn in sorted(noisy, key=lambda r: r["samples"]):
        rd = next((r for r in den if r["samples"] == rn["samples"]), None)
        if rd and int(rn["samples"]) in set([1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 8192]):
            prow.append(
                [
                    int(rn["samples"]),
                    f"{rn['total_seconds']:.2f}",
                    f"{rd['total_seconds']:.2f}",
                    f"{rn['psnr_db']:.2f}",
                    f"{rd['psnr_db']:.2f}",
                    f"{rn['ssim']:.4f}",
                    f"{rd['ssim']:.4f}",
                    f"{rn['flip']:.4f}",
                    f"{rd['flip']:.4f}",
                ]
            )
    lines += [
        table(
            ["spp", "s noisy", "s denoised", "PSNR noisy", "PSNR dn", "SSIM noisy", "SSIM dn", "FLIP noisy", "FLIP dn"],
            prow,
        ),
        "",
        "![progressive](plots/cornell-box-progressive.png)",
        "",
    ]

    # Dataset.
    if ds_mean:
        lines += [
            f"## Held-out test scenes ({', '.join(ds_names)})",
            "",
            f"Noisy levels as rendered by `make reference noisy`; references of {args.dataset_ref_spp} spp with their own "
            "seed (`EVAL_HELDOUT_REF_SPP`; the dataset's own when it equals `REF_SPP`), so the error floor at high spp is "
            "partly the reference's own noise. Means over the scenes.",
            "",
        ]
        rows = [
            [
                m["estimator"],
                m["samples"],
                m["scenes"],
                f"{m['total_seconds']:.2f}",
                f"{m['psnr_db']:.2f}",
                f"{m['ssim']:.4f}",
                f"{m['flip']:.4f}",
                f"{m['rel_mse']:.3e}",
            ]
            for m in ds_mean
        ]
        lines += [
            table(["estimator", "spp / paths", "scenes", "seconds", "PSNR dB", "SSIM", "FLIP", "relMSE"], rows),
            "",
        ]
        for key, label in METRICS:
            front = pareto([(m["total_seconds"], m[key], f"{m['estimator']} {m['samples']}") for m in ds_mean])
            lines.append(f"- Pareto front in {label}: " + front_text(front))
        lines += [
            "",
            "![dataset error vs time](plots/dataset-time.png)",
            "",
            "![dataset error vs samples](plots/dataset-samples.png)",
            "",
        ]

    if ds_mean:
        lines += peer_table(ds_mean, f"held-out scenes, mean over {len(ds_names)}") + gap_table(ds_rows, ds_names)
    else:
        lines += ["## Held-out test scenes", "", "Not scored in this summary: no dataset reports were given.", ""]

    lines += public_section(public or {}, args.public_ref_spp)

    # Sensors.
    lines += [
        "## Local estimate at sensors vs exact solutions",
        "",
        f"The cases of `make validate` at {args.sensor_scale:g}× its path counts; z = (estimate − exact) / standard error, "
        "mean z² ≈ 1 for an unbiased estimate with honest errors (the 5.8 row compares one area-weighted mean).",
        "",
        table(["case", "kind", "points", "paths", "seconds", "max abs z", "mean z²", "RMS rel. error"], sensor_rows),
        "",
    ]
    lines += ["Per-image and per-point numbers: `reports/csv/*.csv` and `*.ron`.", ""]
    (reports / "summary.md").write_text("\n".join(lines))
    print(f"eval: wrote {reports / 'summary.md'}")


if __name__ == "__main__":
    main()
