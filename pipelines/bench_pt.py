"""`make bench-pt`: speed at equal error of luxest's image estimators against Mitsuba 3 on the same
scene in the same run. Path tracing: `trace` against Mitsuba's `path`; light transport from the
lights: the light tracer (`estimate image --light-tracing`) and the double local estimate
(`estimate image`) against Mitsuba's `ptracer`. For each repetition and each budget every
method renders in turn (interleaved: the machine is shared); `evaluate images` scores every image
against an independent converged reference; the table gives CPU seconds (luxest: the process,
user + system; Mitsuba: loading and rendering, JIT included), samples (or light paths) per
CPU-second, relMSE, and the CPU seconds to reach relMSE 1e-3, from the largest budget's
relMSE x CPU-seconds (relMSE falls as 1/time at these budgets; the measured points are in the
table). Mitsuba's columns need .venv-peers (`scripts/setup.sh --no-python --no-ort --peers`)."""
import argparse
import csv
import os
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
from luxest_contract import image_name  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from atomic import write_text  # noqa: E402

TARGET = 1e-3
MITSUBA = Path(__file__).resolve().parent / "mitsuba_render.py"


def child_cpu(cmd):
    """Runs `cmd`; returns (its user + system CPU seconds, stdout)."""
    r0 = os.times()
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    r1 = os.times()
    if p.returncode != 0:
        sys.exit(f"error: {' '.join(map(str, cmd))} failed:\n{p.stderr.strip()}")
    return (r1.children_user - r0.children_user) + (r1.children_system - r0.children_system), p.stdout


def counts(text):
    return [int(v) for v in text.split(",") if v]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", required=True, help="compiled scene (.lxs)")
    ap.add_argument("--mitsuba-scene", help="the same scene exported for Mitsuba (scene.xml)")
    ap.add_argument("--peers-python", help="python of .venv-peers (Mitsuba)")
    ap.add_argument("--reference", required=True, help="converged reference (independent seed)")
    ap.add_argument("--trace", required=True)
    ap.add_argument("--estimate", required=True)
    ap.add_argument("--evaluate", required=True)
    ap.add_argument("--resolution", required=True, help="WIDTHxHEIGHT")
    ap.add_argument("--spp", required=True, help="path tracing: comma-separated samples per pixel")
    ap.add_argument("--lt-paths", default="", help="light tracing: comma-separated light paths")
    ap.add_argument("--dle-paths", default="", help="double local estimate: comma-separated light paths")
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--work-dir", required=True)
    ap.add_argument("-o", "--out", required=True, help="Markdown table")
    a = ap.parse_args(argv)
    work = Path(a.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    peer = bool(a.mitsuba_scene and a.peers_python and Path(a.peers_python).exists())
    w, h = (int(v) for v in a.resolution.split("x"))
    pixels = w * h

    def luxest_trace(rep, spp):
        prefix = work / f"trace_r{rep}"
        cpu, _ = child_cpu([a.trace, a.scene, "--spp", spp, "--resolution", a.resolution, "--seed", rep, "-o", prefix])
        return cpu, work / image_name(prefix.name, "hdr", spp)

    def luxest_image(extra, tag):
        def run(rep, paths):
            out = work / image_name(f"{tag}_r{rep}", "hdr", paths, unit="le")
            cpu, _ = child_cpu([a.estimate, "image", a.scene, "--paths", paths, "--resolution", a.resolution,
                                "--seed", rep, "-o", out, *extra])
            return cpu, out
        return run

    def mitsuba(integrator, per_pixel):
        def run(rep, budget):
            out = work / f"mitsuba_{integrator}_r{rep}_{budget}.exr"
            # ptracer's sample count is light paths per pixel of the film.
            spp = budget if per_pixel else max(1, round(budget / pixels))
            _, text = child_cpu([a.peers_python, MITSUBA, a.mitsuba_scene, "--spp", spp, "--seed", rep,
                                 "--resolution", a.resolution, "--integrator", integrator, "-o", out])
            return float(text.split()[-3]), out
        return run

    # (name, unit, budgets, samples per budget unit, runner)
    methods = [("luxest trace", "spp", counts(a.spp), pixels, luxest_trace)]
    if peer:
        methods.append(("Mitsuba 3 llvm_ad_rgb path", "spp", counts(a.spp), pixels, mitsuba("path", True)))
    if a.lt_paths:
        methods.append(("luxest light tracer", "paths", counts(a.lt_paths), 1, luxest_image(["--light-tracing"], "lt")))
        if peer:
            methods.append(("Mitsuba 3 llvm_ad_rgb ptracer", "paths", counts(a.lt_paths), 1, mitsuba("ptracer", False)))
    if a.dle_paths:
        methods.append(("luxest double local estimate", "paths", counts(a.dle_paths), 1, luxest_image([], "dle")))
    runs = []  # (method, rep, budget, cpu, image)
    for rep in range(1, a.reps + 1):
        for k in range(max(len(m[2]) for m in methods)):
            for name, _, budgets, _, run in methods:
                if k < len(budgets):
                    cpu, image = run(rep, budgets[k])
                    runs.append((name, rep, budgets[k], cpu, str(image)))
    report = work / "scores.csv"
    subprocess.run([a.evaluate, "images", "--reference", a.reference, *[r[4] for r in runs], "-o", str(report)],
                   check=True, capture_output=True)
    rel = {row["image"]: float(row["rel_mse"]) for row in csv.DictReader(open(report))}
    lines = [f"Speed at equal error: `{a.scene}` at {a.resolution}, reference `{a.reference}`, {a.reps} interleaved "
             f"repetitions ({time.strftime('%Y-%m-%d %H:%M')}).", "",
             "| method | budget | CPU-s (each rep) | M samples or paths / CPU-s | relMSE (each rep) |",
             "|---|---|---|---|---|"]
    to_target = {}
    for name, unit, budgets, per_unit, _ in methods:
        for b in budgets:
            rs = [r for r in runs if r[0] == name and r[2] == b]
            cpus = [r[3] for r in rs]
            errs = [rel.get(Path(r[4]).name, rel.get(r[4])) for r in rs]
            rate = per_unit * b / (sum(cpus) / len(cpus)) / 1e6
            lines.append(f"| {name} | {b} {unit} | {', '.join(f'{c:.2f}' for c in cpus)} | {rate:.3g} | "
                         f"{', '.join(f'{e:.3e}' for e in errs)} |")
            if b == budgets[-1]:
                to_target[name] = sum(c * e for c, e in zip(cpus, errs)) / len(cpus) / TARGET
    lines += ["", f"| method | CPU-s to relMSE {TARGET:g} |", "|---|---|"]
    lines += [f"| {n} | {t:.1f} |" for n, t in to_target.items()]
    lines.append("")
    if peer:
        pt = to_target["luxest trace"] / to_target["Mitsuba 3 llvm_ad_rgb path"]
        lines.append(f"luxest trace / Mitsuba path, CPU time to relMSE {TARGET:g}: {pt:.2f} (issue 13's target: at most 0.5).")
        if "Mitsuba 3 llvm_ad_rgb ptracer" in to_target:
            for n in ("luxest light tracer", "luxest double local estimate"):
                if n in to_target:
                    lines.append(f"{n} / Mitsuba ptracer, CPU time to relMSE {TARGET:g}: "
                                 f"{to_target[n] / to_target['Mitsuba 3 llvm_ad_rgb ptracer']:.2f}.")
    else:
        lines.append("Mitsuba not installed (`scripts/setup.sh --no-python --no-ort --peers`): no peer rows.")
    write_text(a.out, "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
