"""`make bench-pt`: speed at equal error of luxest's image estimators against Mitsuba 3 on the same
scene in the same run. Path tracing: `trace` against Mitsuba's `path`; light transport from the
lights: the light tracer (`estimate image --light-tracing`) and the double local estimate
(`estimate image`, combined with light tracing by multiple importance sampling, and plain with
`--mis-paths 0`) against Mitsuba's `ptracer`. Variants of `trace` (`--trace-variant
LABEL=EXTRA_ARGS`, repeatable: e.g. `power=--light-sampler power` for the flux-proportional light
choice beside the light BVH, `no-portals=--portals off` for a daylit room without its window
portals) are rows of their own, rendered interleaved with the rest at the trace budgets and
compared with Mitsuba's `path` as the main trace row is. Mitsuba runs with each of its samplers
(`--mitsuba-samplers`: independent, stratified, ldsampler, multijitter), one row each, and the
report compares luxest with Mitsuba at its best: for each target relMSE, the sampler that
reaches it in the least CPU time, named. For each repetition and each budget every
method renders in turn (interleaved: the machine is shared); `evaluate images` scores every image
against an independent converged reference; the table gives CPU seconds (luxest: the process,
user + system; Mitsuba: loading and rendering, JIT included), samples (or light paths) per
CPU-second, relMSE, and the CPU seconds to reach relMSE 1e-2 and 1e-3, each from the budget
whose relMSE is nearest (log scale) as relMSE x CPU-seconds / target (relMSE falls as 1/time at
these budgets; the measured points are in the table). The host (CPU model, AVX2 or AVX-512)
heads the report: Mitsuba's LLVM backend is twice as wide on AVX-512. Mitsuba's rows need
.venv-peers (`scripts/setup.sh --no-python --no-ort --peers`)."""

import argparse
import csv
import math
import os
import re
import shlex
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
DLE = "luxest double local estimate"
DLE_PLAIN = "luxest double local estimate, plain"
MITSUBA_SAMPLERS = "independent,stratified,ldsampler,multijitter"
# The targets for luxest trace / Mitsuba path at its best, CPU time to relMSE 1e-3.
PATH_TARGET = {"AVX-512": 1.0, "AVX2": 0.5}


def mitsuba_name(integrator, sampler):
    return f"Mitsuba 3 llvm_ad_rgb {integrator}, {sampler}"


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


TRACE = "luxest trace"


def trace_variant(text):
    """`LABEL=EXTRA_ARGS` -> (row name, extra `trace` arguments); argparse's type for
    --trace-variant (a bad value is a usage error naming it)."""
    label, sep, extra = text.partition("=")
    label = label.strip()
    args = shlex.split(extra)
    if not sep or not label or not args or not re.fullmatch(r"[A-Za-z0-9_.+-]+", label):
        raise argparse.ArgumentTypeError(
            f"{text!r}: expected LABEL=EXTRA_ARGS (LABEL of letters, digits, _ . + -; arguments not empty)"
        )
    return f"{TRACE}, {label}", args


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", required=True, help="compiled scene (.lxs)")
    ap.add_argument("--mitsuba-scene", help="the same scene exported for Mitsuba (scene.xml)")
    ap.add_argument("--peers-python", help="python of .venv-peers (Mitsuba)")
    ap.add_argument("--reference", required=True, help="converged reference (independent seed)")
    ap.add_argument("--trace", required=True)
    ap.add_argument("--estimate", required=True)
    ap.add_argument("--evaluate", required=True)
    ap.add_argument("--resolution", required=True, help="WIDTHxHEIGHT")
    ap.add_argument("--spp", required=True, help="path tracing: comma-separated samples per pixel")
    ap.add_argument(
        "--trace-variant",
        type=trace_variant,
        action="append",
        default=[],
        metavar="LABEL=EXTRA_ARGS",
        help="a further trace row with these extra arguments (repeatable), e.g. power=--light-sampler power",
    )
    ap.add_argument("--lt-paths", default="", help="light tracing: comma-separated light paths")
    ap.add_argument("--dle-paths", default="", help="double local estimate: comma-separated light paths")
    ap.add_argument(
        "--dle-mis-paths",
        type=int,
        default=10000,
        help="its light-tracing paths per light path (estimate image --mis-paths)",
    )
    ap.add_argument(
        "--dle-plain-paths",
        default="",
        help="the plain double local estimate (--mis-paths 0): comma-separated light paths",
    )
    ap.add_argument(
        "--mitsuba-samplers",
        default=MITSUBA_SAMPLERS,
        help=f"Mitsuba's samplers, one row each (comma-separated; default {MITSUBA_SAMPLERS})",
    )
    ap.add_argument(
        "--path-target",
        type=float,
        help="the issue's target for trace / Mitsuba path at its best at relMSE 1e-3 on this scene "
        "(default: the Cornell box's, by host: " + ", ".join(f"{v:g} on {k}" for k, v in PATH_TARGET.items()) + ")",
    )
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--work-dir", required=True)
    ap.add_argument("-o", "--out", required=True, help="Markdown table")
    ap.add_argument("--plot", help="also plot relMSE against CPU-s (PNG)")
    a = ap.parse_args(argv)
    work = Path(a.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    peer = bool(a.mitsuba_scene and a.peers_python and Path(a.peers_python).exists())
    w, h = (int(v) for v in a.resolution.split("x"))
    pixels = w * h
    samplers = [v for v in a.mitsuba_samplers.split(",") if v]

    def luxest_trace(tag, extra):
        def run(rep, spp):
            prefix = work / f"{tag}_r{rep}"
            cpu, _ = child_cpu(
                [a.trace, a.scene, "--spp", spp, "--resolution", a.resolution, "--seed", rep, "-o", prefix, *extra]
            )
            return cpu, work / image_name(prefix.name, "hdr", spp), spp * pixels

        return run

    def luxest_image(extra, tag):
        def run(rep, paths):
            out = work / image_name(f"{tag}_r{rep}", "hdr", paths, unit="le")
            cpu, _ = child_cpu(
                [
                    a.estimate,
                    "image",
                    a.scene,
                    "--paths",
                    paths,
                    "--resolution",
                    a.resolution,
                    "--seed",
                    rep,
                    "-o",
                    out,
                    *extra,
                ]
            )
            return cpu, out, paths

        return run

    def mitsuba(integrator, sampler, per_pixel):
        def run(rep, budget):
            out = work / f"mitsuba_{integrator}_{sampler}_r{rep}_{budget}.exr"
            # ptracer's sample count is light paths per pixel of the film.
            spp = budget if per_pixel else max(1, round(budget / pixels))
            _, text = child_cpu(
                [
                    a.peers_python,
                    MITSUBA,
                    a.mitsuba_scene,
                    "--spp",
                    spp,
                    "--seed",
                    rep,
                    "--resolution",
                    a.resolution,
                    "--integrator",
                    integrator,
                    "--sampler",
                    sampler,
                    "-o",
                    out,
                ]
            )
            # `cpu_seconds <s> wall_seconds <s> sample_count <n>`, after Mitsuba's own log lines (a
            # sampler that rounds the count warns, with colour codes): samplers round the count.
            m = re.search(r"cpu_seconds (\S+) wall_seconds \S+ sample_count (\d+)", text)
            if m is None:
                sys.exit(f"error: {MITSUBA}: no timing line in its output:\n{text.strip()}")
            cpu, spp_used = float(m.group(1)), int(m.group(2))
            return cpu, out, spp_used * pixels

        return run

    # (name, unit, budgets, samples per budget unit, runner)
    methods = [(TRACE, "spp", counts(a.spp), pixels, luxest_trace("trace", []))]
    for k, (name, extra) in enumerate(a.trace_variant):
        if any(m[0] == name for m in methods):
            sys.exit(f"error: --trace-variant: the row {name!r} is given twice")
        methods.append((name, "spp", counts(a.spp), pixels, luxest_trace(f"trace_v{k + 1}", extra)))
    if peer:
        for sm in samplers:
            methods.append((mitsuba_name("path", sm), "spp", counts(a.spp), pixels, mitsuba("path", sm, True)))
    if a.lt_paths:
        methods.append(("luxest light tracer", "paths", counts(a.lt_paths), 1, luxest_image(["--light-tracing"], "lt")))
        if peer:
            for sm in samplers:
                methods.append(
                    (mitsuba_name("ptracer", sm), "paths", counts(a.lt_paths), 1, mitsuba("ptracer", sm, False))
                )
    if a.dle_paths:
        methods.append(
            (
                DLE,
                f"paths (+{a.dle_mis_paths} light-tracing paths each)",
                counts(a.dle_paths),
                1,
                luxest_image(["--mis-paths", a.dle_mis_paths], "dle"),
            )
        )
    if a.dle_plain_paths:
        methods.append((DLE_PLAIN, "paths", counts(a.dle_plain_paths), 1, luxest_image(["--mis-paths", 0], "dleplain")))
    runs = []  # (method, rep, budget, cpu, image, samples or paths traced)
    for rep in range(1, a.reps + 1):
        for k in range(max(len(m[2]) for m in methods)):
            for name, _, budgets, _, run in methods:
                if k < len(budgets):
                    cpu, image, done = run(rep, budgets[k])
                    runs.append((name, rep, budgets[k], cpu, str(image), done))
    report = work / "scores.csv"
    subprocess.run(
        [a.evaluate, "images", "--reference", a.reference, *[r[4] for r in runs], "-o", str(report)],
        check=True,
        capture_output=True,
    )
    rel = {row["image"]: float(row["rel_mse"]) for row in csv.DictReader(open(report))}
    host = host_summary()
    lines = [
        f"Speed at equal error: `{a.scene}` at {a.resolution}, reference `{a.reference}`, {a.reps} interleaved "
        f"repetitions ({time.strftime('%Y-%m-%d %H:%M')}; host: {host}).",
        "",
        (
            "Mitsuba's samplers round the sample count (multijitter to a product of near factors, "
            "ldsampler to a power of two): the rate column counts the samples they traced."
        ),
        "",
        "| method | budget | CPU-s (each rep) | M samples or paths / CPU-s | relMSE (each rep) |",
        "|---|---|---|---|---|",
    ]
    to_target = {}  # (method, target) -> CPU-s
    for name, unit, budgets, per_unit, _ in methods:
        points = []  # (mean relMSE, mean relMSE x CPU-s)
        for b in budgets:
            rs = [r for r in runs if r[0] == name and r[2] == b]
            cpus = [r[3] for r in rs]
            errs = [rel.get(Path(r[4]).name, rel.get(r[4])) for r in rs]
            rate = sum(r[5] for r in rs) / sum(cpus) / 1e6
            lines.append(
                f"| {name} | {b} {unit} | {', '.join(f'{c:.2f}' for c in cpus)} | {rate:.3g} | "
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
        lines.append(f"| {name} | " + " | ".join(f"{to_target[name, t]:.2f}" for t in TARGETS) + " |")
    lines.append("")
    lines += against_variants(to_target)
    if peer:
        lines += at_its_best(to_target, samplers, host, a.path_target)
    else:
        lines.append("Mitsuba not installed (`scripts/setup.sh --no-python --no-ort --peers`): no peer rows.")
    if a.plot:
        plot(a.plot, runs, rel, methods, f"{Path(a.scene).parent.name} {a.resolution}", host)
    write_text(a.out, "\n".join(lines) + "\n")
    print("\n".join(lines))


def trace_rows(to_target):
    """The trace rows scored: the main one first, then its variants in the order given."""
    names = [n for n, t in to_target if t == TARGETS[0] and (n == TRACE or n.startswith(TRACE + ", "))]
    return sorted(names, key=lambda n: n != TRACE)


def against_variants(to_target):
    """Lines comparing the main trace row with each variant: CPU time to equal relMSE, main over
    variant (below 1: the default is faster)."""
    lines = []
    for name in trace_rows(to_target)[1:]:
        ratios = ", ".join(f"{to_target[TRACE, t] / to_target[name, t]:.2f} at {t:g}" for t in TARGETS)
        lines.append(f"{TRACE} / {name}, CPU time to equal relMSE: {ratios}.")
    return lines + [""] if lines else lines


def best_sampler(to_target, integrator, samplers, t):
    """The sampler with which Mitsuba's `integrator` reaches relMSE `t` in the least CPU time."""
    return min(samplers, key=lambda sm: to_target[mitsuba_name(integrator, sm), t])


def at_its_best(to_target, samplers, host, path_target=None):
    """The report's closing lines: Mitsuba's best sampler per integrator and target, and luxest's
    CPU time to equal error over Mitsuba's at its best (and with each sampler); the main trace
    row names its target: `path_target` where given, else the Cornell box's for the host."""
    lines = []
    # host_summary ends in "AVX-512", "AVX2 (no AVX-512)" or "no AVX2".
    simd = "AVX-512" if host.endswith(", AVX-512") else "AVX2"
    pairs = [(n, "path") for n in trace_rows(to_target)]
    pairs += [(n, "ptracer") for n in ("luxest light tracer", DLE, DLE_PLAIN) if (n, TARGETS[0]) in to_target]
    for integrator in ("path", "ptracer"):
        if (mitsuba_name(integrator, samplers[0]), TARGETS[0]) not in to_target:
            continue
        best = ", ".join(f"{best_sampler(to_target, integrator, samplers, t)} at relMSE {t:g}" for t in TARGETS)
        lines.append(
            f"Mitsuba {integrator} at its best (least CPU time to the relMSE among {', '.join(samplers)}): {best}."
        )
        for name, peer in pairs:
            if peer != integrator:
                continue
            ratios = []
            for t in TARGETS:
                sm = best_sampler(to_target, integrator, samplers, t)
                ratios.append(f"{to_target[name, t] / to_target[mitsuba_name(integrator, sm), t]:.2f} at {t:g} ({sm})")
            note = ""
            if name == TRACE and path_target is not None:
                note = f" The target at {TARGETS[-1]:g} on this scene: at most {path_target:g}."
            elif name == TRACE:
                note = (
                    f" The target at {TARGETS[-1]:g}: at most {PATH_TARGET[simd]:g} on this {simd} host "
                    f"({', '.join(f'{v:g} on {k}' for k, v in PATH_TARGET.items())})."
                )
            lines.append(
                f"{name} / Mitsuba {integrator} at its best, CPU time to equal relMSE: {', '.join(ratios)}.{note}"
            )
            each = ", ".join(
                f"{sm} {to_target[name, TARGETS[-1]] / to_target[mitsuba_name(integrator, sm), TARGETS[-1]]:.2f}"
                for sm in samplers
            )
            lines.append(f"{name} / Mitsuba {integrator} with each sampler at {TARGETS[-1]:g}: {each}.")
    return lines


def plot(path, runs, rel, methods, title, host):
    """relMSE against CPU seconds, log-log: each method's mean over the repetitions per budget,
    joined (Mitsuba dashed, each method its own colour), with the targets as grey lines.
    Written atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5), dpi=110)
    colours = plt.get_cmap("tab20").colors  # 20 distinct colours: one per method
    for k, (name, _, budgets, _, _) in enumerate(methods):
        xs, ys = [], []
        for b in budgets:
            rs = [r for r in runs if r[0] == name and r[2] == b]
            cpus = [r[3] for r in rs]
            errs = [rel.get(Path(r[4]).name, rel.get(r[4])) for r in rs]
            xs.append(sum(cpus) / len(cpus))
            ys.append(sum(errs) / len(errs))
        dashed = name.startswith("Mitsuba")
        ax.loglog(xs, ys, "o--" if dashed else "o-", label=name, markersize=4, color=colours[k % len(colours)])
    for t in TARGETS:
        ax.axhline(t, color="0.8", linewidth=0.8, zorder=0)
    ax.set_xlabel(f"CPU seconds ({host})")
    ax.set_ylabel("relMSE against the converged reference")
    ax.set_title(f"Error against CPU time: {title}")
    ax.grid(True, which="both", color="0.93")
    ax.legend(fontsize=6)
    fig.tight_layout()
    tmp = Path(path).with_name(Path(path).name + ".tmp.png")
    fig.savefig(tmp)
    os.replace(tmp, path)


if __name__ == "__main__":
    main()
