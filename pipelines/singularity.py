#!/usr/bin/env python3
"""`make singularity`: bias and variance of the local estimate's kernel regularisation at the
corners and edges of the Cornell box, against eps, for `ball` and `clamp`.

For each eps (as a fraction of the room scale, the box height 0.5488 m); the sensors on
corners/edges are evaluated at the default edge offset (1e-3 of the room scale) off the adjacent
surfaces (see estimate/src/placement.rs), and the reference at the same points is the backward
`gather` estimator, which has no singularity.
Reported per eps and mode: mean |bias| / reference, mean relative standard error, and the
relative RMS error sqrt(bias² + se²) at a fixed number of light paths. Standard library only.
"""
import csv
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "build" / "singularity"
ROOM = 0.5488


def corners_scene():
    text = (ROOT / "scenes" / "cornell-box.ron").read_text()
    head = text[: text.index("    sensors: [")]
    body = text[text.index("    sensors: ["):]
    corners = body[body.index("        Points(name: \"corners\""): body.index("        // The floor")]
    return head + "    sensors: [\n" + corners + "    ],\n)\n"


def read(path):
    with open(path) as f:
        return [(float(r["value_lx"]), float(r["standard_error_lx"])) for r in csv.DictReader(f)]


def measure(estimate_bin, lxs, ref, tag, paths, extra):
    """Runs the local estimate; returns mean |bias|/ref, se/ref, rms error and seconds."""
    le_csv = OUT / f"{tag}.csv"
    r = subprocess.run([estimate_bin, "sensors", lxs, "-o", OUT / f"{tag}.ron", "--csv", le_csv,
                        "--paths", str(paths), "--seed", "12", *extra],
                       check=True, stderr=subprocess.PIPE, text=True)
    seconds = float(r.stderr.strip().split()[-2])
    le = read(le_csv)
    bias = [abs(v - rv) / rv for (v, _), (rv, _) in zip(le, ref)]
    se = [s / rv for (_, s), (rv, _) in zip(le, ref)]
    rms = [(b * b + s * s) ** 0.5 for b, s in zip(bias, se)]
    n = len(le)
    return sum(bias) / n, sum(se) / n, sum(rms) / n, seconds


def main():
    preset = os.environ.get("PRESET", "quick")
    paths = 1_000_000 if preset == "quick" else 10_000_000
    samples = 200_000 if preset == "quick" else 2_000_000
    compile_bin = os.environ.get("SCENE_COMPILE", str(ROOT / "target/release/scene-compile"))
    estimate_bin = os.environ.get("ESTIMATE", str(ROOT / "target/release/estimate"))
    OUT.mkdir(parents=True, exist_ok=True)
    ron, lxs = OUT / "cornell-corners.ron", OUT / "cornell-corners.lxs"
    ron.write_text(corners_scene())
    subprocess.run([compile_bin, ron, "-o", lxs, "-q"], check=True)
    print(f"Cornell box corner/edge sensors: local estimate ({paths} paths) vs gather reference ({samples} samples/sensor)")
    print(f"{'eps/room':>9} {'eps (m)':>9} {'mode':>6} {'|bias|/ref':>11} {'se/ref':>9} {'rms err':>9} {'time (s)':>9}")
    ref_csv = OUT / "gather.csv"
    subprocess.run([estimate_bin, "gather", lxs, "-o", OUT / "gather.ron", "--csv", ref_csv,
                    "--samples", str(samples), "--seed", "11"], check=True, stderr=subprocess.DEVNULL)
    ref = read(ref_csv)
    print("reference (lx): " + ", ".join(f"{v:.4f}±{s:.4f}" for v, s in ref))
    for frac in [1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 1e-1]:
        eps = frac * ROOM
        for mode in ["ball", "clamp"]:
            bias, se, rms, seconds = measure(estimate_bin, lxs, ref, f"le-{mode}-{frac}", paths,
                                             ["--eps", str(eps), "--singularity", mode, "--near-samples", "0"])
            print(f"{frac:>9.0e} {eps:>9.2e} {mode:>6} {bias:>11.3e} {se:>9.3e} {rms:>9.3e} {seconds:>9.2f}")
            sys.stdout.flush()
    print("Near-field split (collisions closer than R estimated backwards, 20000 samples/sensor), default eps:")
    print(f"{'R/room':>9} {'R (m)':>9} {'':>6} {'|bias|/ref':>11} {'se/ref':>9} {'rms err':>9} {'time (s)':>9}")
    for frac in [3e-3, 1e-2, 3e-2, 1e-1]:
        radius = frac * ROOM
        bias, se, rms, seconds = measure(estimate_bin, lxs, ref, f"le-near-{frac}", paths, ["--near-radius", str(radius)])
        print(f"{frac:>9.0e} {radius:>9.2e} {'split':>6} {bias:>11.3e} {se:>9.3e} {rms:>9.3e} {seconds:>9.2f}")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
