"""`make bench-portals`: CPU time to equal error of `trace` on a daylit interior with and without
its window portals (`trace --portals auto|off`) against Mitsuba 3's `path` with each of the given
samplers, on the same scene in the same run. For each repetition and each budget every method
renders in turn (interleaved: the machine is shared); `evaluate images` scores every image
against an independent converged reference. CPU seconds: luxest, the process's user + system;
Mitsuba, loading and rendering with JIT compilation (what pipelines/mitsuba_render.py prints).
CPU seconds to a relMSE target are taken, as in pipelines/bench_pt.py, from the budget whose
relMSE is nearest (log scale) as relMSE x CPU-seconds / target. Mitsuba's samplers are chosen by
writing a copy of the exported scene beside it with the sampler's type replaced."""

import argparse
import csv
import math
import os
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
from luxest_contract import image_name  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from atomic import write_text  # noqa: E402
from host import host_summary  # noqa: E402

TARGETS = (1e-2, 1e-3)
MITSUBA = Path(__file__).resolve().parent / "mitsuba_render.py"
PORTALS = "luxest trace, portals"
NO_PORTALS = "luxest trace, --portals off"


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


def with_sampler(xml, sampler):
    """A copy of the exported Mitsuba scene `xml` beside it, with `sampler` in place of the
    exported `independent` (the file itself for `independent`)."""
    if sampler == "independent":
        return Path(xml)
    text = Path(xml).read_text()
    if '<sampler type="independent">' not in text:
        sys.exit(f"error: {xml}: no independent sampler to replace")
    out = Path(xml).with_name(f"{Path(xml).stem}.{sampler}.xml")
    out.write_text(text.replace('<sampler type="independent">', f'<sampler type="{sampler}">', 1))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", required=True, help="compiled scene (.lxs) with portals")
    ap.add_argument("--reference", required=True, help="converged reference (independent seed)")
    ap.add_argument("--mitsuba-scene", help="the same scene exported for Mitsuba (scene.xml)")
    ap.add_argument("--peers-python", help="python of .venv-peers (Mitsuba)")
    ap.add_argument("--trace", required=True)
    ap.add_argument("--evaluate", required=True)
    ap.add_argument("--resolution", required=True, help="WIDTHxHEIGHT")
    ap.add_argument("--spp", required=True, help="trace with portals: comma-separated samples per pixel")
    ap.add_argument("--spp-off", required=True, help="trace --portals off: comma-separated samples per pixel")
    ap.add_argument("--mitsuba-spp", required=True, help="Mitsuba: comma-separated samples per pixel")
    ap.add_argument("--mitsuba-samplers", default="independent,multijitter")
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--work-dir", required=True)
    ap.add_argument("-o", "--out", required=True, help="Markdown table")
    a = ap.parse_args(argv)
    work = Path(a.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    peer = bool(a.mitsuba_scene and a.peers_python and Path(a.peers_python).exists())

    def luxest(portals):
        def run(rep, spp):
            prefix = work / f"trace_{portals}_r{rep}"
            cmd = [a.trace, a.scene, "--spp", spp, "--resolution", a.resolution, "--seed", rep]
            cpu, _ = child_cpu([*cmd, "--portals", portals, "-o", prefix])
            return cpu, work / image_name(prefix.name, "hdr", spp)

        return run

    def mitsuba(sampler):
        xml = with_sampler(a.mitsuba_scene, sampler)

        def run(rep, spp):
            out = work / f"mitsuba_{sampler}_r{rep}_{spp}.exr"
            _, text = child_cpu(
                [
                    a.peers_python,
                    MITSUBA,
                    xml,
                    "--spp",
                    spp,
                    "--seed",
                    rep,
                    "--resolution",
                    a.resolution,
                    "-o",
                    out,
                ]
            )
            return float(text.split()[-3]), out

        return run

    methods = [(PORTALS, counts(a.spp), luxest("auto")), (NO_PORTALS, counts(a.spp_off), luxest("off"))]
    if peer:
        for s in a.mitsuba_samplers.split(","):
            methods.append((f"Mitsuba 3 llvm_ad_rgb path, {s}", counts(a.mitsuba_spp), mitsuba(s)))
    runs = []  # (method, rep, spp, cpu, image)
    for rep in range(1, a.reps + 1):
        for k in range(max(len(m[1]) for m in methods)):
            for name, budgets, run in methods:
                if k < len(budgets):
                    cpu, image = run(rep, budgets[k])
                    runs.append((name, rep, budgets[k], cpu, str(image)))
    report = work / "scores.csv"
    subprocess.run(
        [a.evaluate, "images", "--reference", a.reference, *[r[4] for r in runs], "-o", str(report)],
        check=True,
        capture_output=True,
    )
    rel = {row["image"]: float(row["rel_mse"]) for row in csv.DictReader(open(report))}
    lines = [
        f"CPU time to equal error with and without portals: `{a.scene}` at {a.resolution}, reference "
        f"`{a.reference}`, {a.reps} interleaved repetitions ({time.strftime('%Y-%m-%d %H:%M')}; "
        f"{host_summary()}).",
        "",
        "| method | spp | CPU-s (each rep) | M samples / CPU-s | relMSE (each rep) |",
        "|---|---|---|---|---|",
    ]
    w, h = (int(v) for v in a.resolution.split("x"))
    to_target = {}
    for name, budgets, _ in methods:
        points = []
        for b in budgets:
            rs = [r for r in runs if r[0] == name and r[2] == b]
            cpus = [r[3] for r in rs]
            errs = [rel.get(Path(r[4]).name, rel.get(r[4])) for r in rs]
            rate = w * h * b / (sum(cpus) / len(cpus)) / 1e6
            lines.append(
                f"| {name} | {b} | {', '.join(f'{c:.2f}' for c in cpus)} | {rate:.3g} | "
                f"{', '.join(f'{e:.3e}' for e in errs)} |"
            )
            points.append((sum(errs) / len(errs), sum(c * e for c, e in zip(cpus, errs)) / len(cpus)))
        for t in TARGETS:
            _, efficiency = min(points, key=lambda p: abs(math.log(p[0] / t)))
            to_target[name, t] = efficiency / t
    lines += [
        "",
        "| method | " + " | ".join(f"CPU-s to relMSE {t:g}" for t in TARGETS) + " |",
        "|---|" + "---|" * len(TARGETS),
    ]
    for name, *_ in methods:
        lines.append(f"| {name} | " + " | ".join(f"{to_target[name, t]:.3g}" for t in TARGETS) + " |")
    lines.append("")
    t = TARGETS[-1]
    lines.append(
        f"luxest with portals / without, CPU time to relMSE {t:g}: "
        f"{to_target[PORTALS, t] / to_target[NO_PORTALS, t]:.3f}."
    )
    if peer:
        peers = [m[0] for m in methods if m[0].startswith("Mitsuba")]
        best = min(peers, key=lambda n: to_target[n, t])
        lines.append(
            f"luxest with portals / Mitsuba at its best here ({best}), CPU time to relMSE {t:g}: "
            f"{to_target[PORTALS, t] / to_target[best, t]:.3f} (the target: at most 0.5); without portals "
            f"{to_target[NO_PORTALS, t] / to_target[best, t]:.3f}."
        )
    else:
        lines.append("Mitsuba not installed (`scripts/setup.sh --no-python --no-ort --peers`): no peer rows.")
    write_text(a.out, "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
