"""Next-event estimation's light choice at equal error: `trace --light-sampler bvh` (the light
BVH) against `trace --light-sampler power` (flux-proportional) and Mitsuba 3's `path` with a
chosen sampler (default `multijitter`, its best on the Cornell box), on the same scene in the same
run. For each repetition and each budget every method renders in turn (interleaved: the machine is
shared); `evaluate images` scores every image against an independent converged reference; the
table gives CPU seconds (luxest: the process, user + system; Mitsuba: loading and rendering, JIT
included), relMSE, and each method's CPU seconds to relMSE 1e-2 and 1e-3 from the budget whose
relMSE is nearest (log scale) as relMSE x CPU-seconds / target. Mitsuba's column needs
.venv-peers (`scripts/setup.sh --no-python --no-ort --peers`)."""

import argparse
import csv
import math
import os
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from atomic import write_text  # noqa: E402
from host import host_summary  # noqa: E402

TARGETS = (1e-2, 1e-3)

# Mitsuba 3's path tracer on an exported scene with the sampler replaced; prints its CPU seconds.
MITSUBA = """
import sys, time
sys.path.insert(0, {pipelines!r})
import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
import drjit as dr
from mitsuba_render import scene_xml
xml = scene_xml(mi, {scene!r}, {resolution!r}, "path")
xml = xml.replace('<sampler type="independent"', '<sampler type="{sampler}"', 1)
assert 'type="{sampler}"' in xml, "no sampler element to replace"
t = time.process_time()
s = mi.load_string(xml, spp={spp})
img = mi.render(s, seed={seed})
dr.eval(img)
dr.sync_thread()
cpu = time.process_time() - t
mi.util.write_bitmap({out!r}, img, write_async=False)
print("cpu_seconds", cpu)
"""


def child_cpu(cmd):
    """Runs `cmd`; returns (its user + system CPU seconds, stdout)."""
    r0 = os.times()
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    r1 = os.times()
    if p.returncode != 0:
        sys.exit(f"error: {' '.join(map(str, cmd))} failed:\n{p.stderr.strip()}")
    return (r1.children_user - r0.children_user) + (r1.children_system - r0.children_system), p.stdout


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", required=True, help="compiled scene (.lxs)")
    ap.add_argument("--mitsuba-scene", help="the same scene exported for Mitsuba (scene.xml)")
    ap.add_argument("--peers-python", help="python of .venv-peers (Mitsuba)")
    ap.add_argument("--mitsuba-sampler", default="multijitter")
    ap.add_argument("--reference", required=True, help="converged reference (independent seed)")
    ap.add_argument("--trace", required=True)
    ap.add_argument("--evaluate", required=True)
    ap.add_argument("--resolution", required=True, help="WIDTHxHEIGHT")
    ap.add_argument("--spp", required=True, help="comma-separated samples per pixel")
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--work-dir", required=True)
    ap.add_argument("-o", "--out", required=True, help="Markdown table")
    a = ap.parse_args(argv)
    work = Path(a.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    budgets = [int(v) for v in a.spp.split(",") if v]

    def luxest(sampler):
        def run(rep, spp):
            prefix = work / f"{sampler}_r{rep}"
            cmd = [a.trace, a.scene, "--spp", spp, "--resolution", a.resolution, "--seed", rep]
            cmd += ["--light-sampler", sampler, "-o", prefix, "-q"]
            cpu, _ = child_cpu(cmd)
            return cpu, f"{prefix}_{spp:06}spp.hdr.exr"

        return run

    def mitsuba(rep, spp):
        out = str(work / f"mitsuba_{a.mitsuba_sampler}_r{rep}_{spp}.exr")
        code = MITSUBA.format(
            pipelines=str(Path(__file__).resolve().parent),
            scene=a.mitsuba_scene,
            resolution=a.resolution,
            sampler=a.mitsuba_sampler,
            spp=spp,
            seed=rep,
            out=out,
        )
        _, text = child_cpu([a.peers_python, "-c", code])
        return float(text.split()[-1]), out

    methods = [("luxest trace, light BVH", luxest("bvh")), ("luxest trace, power", luxest("power"))]
    if a.mitsuba_scene and a.peers_python:
        methods.append((f"Mitsuba 3 llvm_ad_rgb path, {a.mitsuba_sampler}", mitsuba))
    runs = []
    for rep in range(1, a.reps + 1):
        for spp in budgets:
            for name, run in methods:
                cpu, image = run(rep, spp)
                runs.append((name, rep, spp, cpu, image))
                print(f"{name} rep {rep} {spp} spp: {cpu:.2f} CPU-s", flush=True)
    report = work / "scores.csv"
    subprocess.run(
        [a.evaluate, "images", "--reference", a.reference, *[r[4] for r in runs], "-o", str(report)],
        check=True,
        capture_output=True,
    )
    with open(report) as f:
        rel = {row["image"]: float(row["rel_mse"]) for row in csv.DictReader(f)}
    lines = [
        f"Light choice at equal error: `{a.scene}` at {a.resolution}, reference `{a.reference}`, "
        f"{a.reps} interleaved repetitions; {host_summary()}.",
        "",
        "| method | spp | CPU-s (each rep) | relMSE (each rep) |",
        "|---|---|---|---|",
    ]
    to_target = {}
    for name, _ in methods:
        points = []
        for spp in budgets:
            rs = [r for r in runs if r[0] == name and r[2] == spp]
            cpus = [r[3] for r in rs]
            errs = [rel[r[4]] for r in rs]
            lines.append(
                f"| {name} | {spp} | {' / '.join(f'{c:.2f}' for c in cpus)} | {' / '.join(f'{e:.3g}' for e in errs)} |"
            )
            points.append((sum(errs) / len(errs), sum(e * c for e, c in zip(errs, cpus)) / len(errs)))
        to_target[name] = [min(points, key=lambda p: abs(math.log(p[0] / t)))[1] / t for t in TARGETS]
    lines += ["", "| method | " + " | ".join(f"CPU-s to relMSE {t:g}" for t in TARGETS) + " |"]
    lines.append("|---|" + "---|" * len(TARGETS))
    for name, ts in to_target.items():
        lines.append(f"| {name} | " + " | ".join(f"{t:.3g}" for t in ts) + " |")
    names = list(to_target)
    lines.append("")
    for other in names[1:]:
        ratios = ", ".join(
            f"{to_target[names[0]][k] / to_target[other][k]:.2f} at {t:g}" for k, t in enumerate(TARGETS)
        )
        lines.append(f"{names[0]} / {other}, CPU time to equal relMSE: {ratios}.")
    write_text(a.out, "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
