"""`make bench-slurm`: what running the Make DAG through Slurm costs on this machine, and what
`PRESET=full` costs in core-hours and GPU-hours (a benchmark, not a test).

1. The overhead of one stage call as a Slurm job step: the same small `trace` run directly and
   through `srun -n1 -c1 --exact`, interleaved, wall-clock seconds per call.
2. `make -jJ reference noisy` of the quick dataset with and without `LAUNCH="srun ..."`, on a
   real single-node cluster (scripts/slurm-cluster.sh), wall-clock seconds; the two datasets
   must have equal pixels.
3. The full preset's cost, extrapolated from the quick dataset's own per-file render seconds
   (`luxest.seconds` × the CPUs that rendered it) by pixels, samples or paths, and rooms; the GPU
   time is the training budget `TRAIN_MINUTES` of the full preset.
Writes a Markdown report."""

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))
sys.path.insert(0, str(ROOT / "pipelines"))
sys.path.insert(0, str(ROOT / "training"))
import config  # noqa: E402
import luxest_contract as contract  # noqa: E402
from host import host_summary  # noqa: E402

STAGES = {"SCENE_COMPILE": "scene-compile", "TRACE": "trace", "AOV_WRITE": "aov-write", "ESTIMATE": "estimate"}


def preset(name, variable):
    """A value of pipelines/presets.mk for PRESET=`name` (training/config.py reads the presets as
    make does); DATASET_SCENES: the generated dataset's scenes for that preset."""
    if variable == "DATASET_SCENES":
        gen = [sys.executable, str(ROOT / "data-gen" / "generate.py"), "--preset", name, "--list"]
        return subprocess.run(gen, capture_output=True, text=True, check=True).stdout.strip()
    return config.presets(name)[variable]


def wall(cmd, env=None):
    start = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, env=env, cwd=ROOT)
    return time.perf_counter() - start


def mean_se(xs):
    return statistics.fmean(xs), statistics.stdev(xs) / len(xs) ** 0.5 if len(xs) > 1 else 0.0


def job_overhead(stages, env, calls, work):
    scene = work / "cb.lxs"
    subprocess.run([stages["SCENE_COMPILE"], str(ROOT / "scenes/cornell-box.ron"), "-o", str(scene), "-q"], check=True)
    cmd = [stages["TRACE"], str(scene), "--spp", "1", "--resolution", "16x16", "--threads", "1", "-o", str(work / "o")]
    srun = ["srun", "-n1", "-c1", "--exact", "--quiet"]
    direct, launched = [], []
    for _ in range(calls):  # interleaved: this machine is shared and noisy
        direct.append(wall(cmd))
        launched.append(wall(srun + cmd, env))
    return mean_se(direct), mean_se(launched)


def make_dataset(stages, name, jobs, env=None, launch=None, count=None):
    for d in (ROOT / "data" / name, ROOT / "build" / "dataset" / name):
        shutil.rmtree(d, ignore_errors=True)
    v = {**stages, "DATASET": name, "PRESET": "quick"}
    if count:
        v["DATASET_COUNT"] = str(count)
    if launch:
        v["LAUNCH"] = launch
    start = time.perf_counter()
    subprocess.run(
        ["make", "--no-print-directory", f"-j{jobs}", "reference", "noisy"] + [f"{k}={x}" for k, x in v.items()],
        cwd=ROOT,
        check=True,
        capture_output=True,
        env=env,
    )
    return time.perf_counter() - start


def same_pixels(a, b):
    da, db = ROOT / "data" / a, ROOT / "data" / b
    files = sorted(p.relative_to(da) for p in da.rglob("*.exr"))
    assert files == sorted(p.relative_to(db) for p in db.rglob("*.exr")), "the datasets have other files"
    return all((contract.read(da / f).pixels == contract.read(db / f).pixels).all() for f in files), len(files)


def family(name):
    """The cost family of a dataset file: reference, its features, a noisy set, its features, a
    local-estimate image."""
    n = contract.parse_image_name(name)
    if n.unit == "le":
        return "le"
    if n.reference:
        return "ref" if n.kind == "hdr" else "ref features"
    return "noisy" if n.kind == "hdr" else "noisy features"


def core_seconds(dataset, cpus):
    """Render core-seconds per family of the dataset's files: one file per render run carries the
    run's seconds, the last snapshot of a set (trace and aov-write write every snapshot of one
    run) and one feature file per aov-write run."""
    runs = {}
    for p in sorted((ROOT / "data" / dataset).rglob("*.exr")):
        n = contract.parse_image_name(p.name)
        if n.kind not in ("hdr", "nrm"):
            continue
        # A noisy set is one run whatever its snapshots; a reference or a local-estimate image is one.
        key = (p.parent, n.name, n.kind, n.reference, n.unit, n.spp if n.unit == "le" else None)
        if key not in runs or (n.spp or 0) > runs[key][0]:
            runs[key] = (n.spp or 0, p)
    per = {}
    for _, p in runs.values():
        seconds = contract.header_value(contract.read(p).header, contract.SECONDS)
        per[family(p.name)] = per.get(family(p.name), 0.0) + seconds * cpus
    return per


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin-dir", required=True, help="the stage programs (target/release)")
    ap.add_argument("--calls", type=int, default=20, help="stage calls per way for the overhead")
    ap.add_argument("--jobs", type=int, default=os.cpu_count())
    ap.add_argument("--count", type=int, help="rooms of the quick dataset (default: the preset's)")
    ap.add_argument("-o", "--out", required=True)
    a = ap.parse_args(argv)
    stages = {k: str(Path(a.bin_dir) / v) for k, v in STAGES.items()}
    cpus = os.cpu_count()
    state = Path(tempfile.mkdtemp(prefix="luxest-slurm-bench-"))
    script = ROOT / "scripts" / "slurm-cluster.sh"
    subprocess.run([str(script), "start", str(state)], check=True, capture_output=True)
    env = {**os.environ, "SLURM_CONF": str(state / "slurm.conf")}
    plain, slurm = "bench-slurm-plain", "bench-slurm-srun"
    launch = "srun --ntasks=1 --cpus-per-task=1 --exact --quiet"
    try:
        (d_mean, d_se), (s_mean, s_se) = job_overhead(stages, env, a.calls, state)
        t_plain = make_dataset(stages, plain, a.jobs, count=a.count)
        t_slurm = make_dataset(stages, slurm, a.jobs, env=env, launch=launch, count=a.count)
        equal, files = same_pixels(plain, slurm)
        # Core-seconds from the run through Slurm: each stage ran bound to one CPU with one
        # thread, so its seconds are its core-seconds (the run without Slurm shares the CPUs
        # among make -j's stages, each running a thread per CPU).
        cost = core_seconds(slurm, 1)
    finally:
        subprocess.run([str(script), "stop", str(state)], capture_output=True)
        shutil.rmtree(state, ignore_errors=True)
    quick_rooms = a.count or len(preset("quick", "DATASET_SCENES").split())
    full_rooms = len(preset("full", "DATASET_SCENES").split())
    side = {p: int(preset(p, "DATASET_SIDE")) for p in ("quick", "full")}
    ref_spp = {p: int(preset(p, "REF_SPP")) for p in ("quick", "full")}
    noisy_max = {p: int(preset(p, "NOISY_LEVELS").split()[-1]) for p in ("quick", "full")}
    dle = {p: sum(int(x) for x in preset(p, "DATASET_DLE").split()) for p in ("quick", "full")}
    pixels = (side["full"] / side["quick"]) ** 2
    rooms = full_rooms / quick_rooms
    scale = {
        "ref": pixels * rooms * ref_spp["full"] / ref_spp["quick"],
        "ref features": pixels * rooms * ref_spp["full"] / ref_spp["quick"],
        "noisy": pixels * rooms * noisy_max["full"] / noisy_max["quick"],
        "noisy features": pixels * rooms * noisy_max["full"] / noisy_max["quick"],
        "le": pixels * rooms * dle["full"] / dle["quick"],
    }
    train_minutes = float(preset("full", "TRAIN_MINUTES"))
    version = subprocess.run([stages["TRACE"], "--version"], capture_output=True, text=True).stdout.strip()
    lines = [
        "# The Make DAG through Slurm: overhead, and the cost of `PRESET=full`",
        "",
        f"Stages: `{a.bin_dir}` ({version}).",
        "",
        f"Host: {host_summary()}; single-node Slurm 22.05 from Debian (scripts/slurm-cluster.sh). "
        "Produced by `make bench-slurm` (pipelines/bench_slurm.py).",
        "",
        "## One stage call as a job step",
        "",
        f"The same `trace` call (Cornell box, 16x16, 1 spp, 1 thread), {a.calls} times each way, interleaved:",
        "",
        "| way | wall-clock s per call |",
        "|---|---|",
        f"| direct | {d_mean:.3f} ± {d_se:.3f} |",
        f"| `srun -n1 -c1 --exact` | {s_mean:.3f} ± {s_se:.3f} |",
        f"| overhead per job step | **{s_mean - d_mean:.3f}** |",
        "",
        "## The quick dataset, `make -j` with and without `LAUNCH`",
        "",
        f"`make -j{a.jobs} reference noisy`, PRESET=quick, {quick_rooms} rooms, release stages; "
        f"LAUNCH=`{launch}`. Pixels of the {files} files equal: {'yes' if equal else '**no**'}. Without a "
        f"launcher each of make's {a.jobs} stages runs a thread per CPU ({cpus}), so the CPUs are shared among "
        "more threads than they have; a step of `-c1` runs one thread on its own CPU.",
        "",
        "| run | wall-clock s |",
        "|---|---|",
        f"| without Slurm | {t_plain:.1f} |",
        f"| through Slurm | {t_slurm:.1f} ({100 * (t_slurm / t_plain - 1):+.1f} %) |",
        "",
        "## What `PRESET=full` costs",
        "",
        "Render core-seconds of the quick dataset's files (`luxest.seconds` of the run through Slurm, where every "
        "stage ran one thread bound to one CPU), scaled to the "
        f"full preset: pixels ({side['full']}² / {side['quick']}²), rooms ({full_rooms} / {quick_rooms}), reference "
        f"spp ({ref_spp['full']} / {ref_spp['quick']}), noisy levels to {noisy_max['full']} spp, local-estimate paths "
        f"({dle['full']} / {dle['quick']} in all per room). The local estimate's images scale with paths × pixels; "
        "renders of larger images keep their per-pixel rate.",
        "",
        "| family | quick, core-s | scale | full, core-hours |",
        "|---|---|---|---|",
    ]
    total = 0.0
    for fam in ("ref", "ref features", "noisy", "noisy features", "le"):
        q = cost.get(fam, 0.0)
        f = q * scale[fam] / 3600
        total += f
        lines.append(f"| {fam} | {q:.1f} | {scale[fam]:.0f} | {f:.1f} |")
    lines += [
        f"| **all renders** | {sum(cost.values()):.1f} | | **{total:.0f}** |",
        "",
        f"Training: the full preset's budget `TRAIN_MINUTES={train_minutes:.0f}`, i.e. "
        f"**{train_minutes / 60:.0f} GPU-hours** on one GPU (`--schedule time` spends exactly the budget), "
        "plus preprocessing on CPUs.",
        "",
    ]
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(a.out).with_suffix(".md.tmp")
    tmp.write_text("\n".join(lines))
    tmp.replace(a.out)
    print("\n".join(lines))
    for name in (plain, slurm):
        for d in (ROOT / "data" / name, ROOT / "build" / "dataset" / name):
            shutil.rmtree(d, ignore_errors=True)


if __name__ == "__main__":
    main()
