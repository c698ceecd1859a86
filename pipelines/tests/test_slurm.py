"""The Make DAG through a real Slurm cluster (`make test-slurm`, part of `make test`).

A single-node cluster — slurmctld, slurmd and munge from Debian's packages, started by
scripts/slurm-cluster.sh under a temporary directory, only its own pids stopped — runs a small
dataset with every stage as a job step (`LAUNCH="srun ..."`); the files must equal those of the
same make run without Slurm (pixels and every header value but the wall-clock seconds). A job
cancelled while its stage runs leaves no partial output, a failed step fails its make target, a
requeued training job resumes from its checkpoint to the uninterrupted run's weights, and
`make -n` plans the same stage commands with and without a launcher, apart from its prefix.

The stage programs are those in LUXEST_BIN_DIR (make test passes target/debug, built before)."""

import json
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import OpenEXR
import pytest

import luxest_contract as contract

ROOT = Path(__file__).resolve().parents[2]
STAGES = {"SCENE_COMPILE": "scene-compile", "TRACE": "trace", "AOV_WRITE": "aov-write", "ESTIMATE": "estimate"}
# A small dataset of every file family: references, noisy levels with their features, and
# local-estimate images, over train, valid and test rooms.
TINY = {
    "DATASET_COUNT": "6",
    "DATASET_SIDE": "16",
    "REF_SPP": "16",
    "NOISY_LEVELS": "1 4",
    "FEATURE_SPP": "4",
    "DATASET_DLE": "10",
}
# Header values that are measurements of the run, not results.
TIMING_KEYS = {contract.SECONDS}


def stage_vars():
    bin_dir = Path(os.environ.get("LUXEST_BIN_DIR", ROOT / "target" / "debug"))
    paths = {var: bin_dir / name for var, name in STAGES.items()}
    missing = [str(p) for p in paths.values() if not p.exists()]
    if missing:
        pytest.fail(
            f"stage programs missing: {', '.join(missing)} (build them first: cargo build, or set LUXEST_BIN_DIR)"
        )
    return {var: str(p) for var, p in paths.items()}


def make(*args, env=None, **variables):
    v = {**stage_vars(), **variables}
    return subprocess.run(
        ["make", "--no-print-directory", *args] + [f"{k}={val}" for k, val in v.items()],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env=env,
    )


@pytest.fixture(scope="module")
def cluster():
    """A running single-node cluster; the environment its clients need (SLURM_CONF)."""
    for tool in ("munged", "slurmctld", "slurmd", "srun"):
        if shutil.which(tool) is None:
            pytest.fail(f"{tool} not found: scripts/setup.sh installs Slurm and munge")
    state = Path(tempfile.mkdtemp(prefix="luxest-slurm-"))
    script = ROOT / "scripts" / "slurm-cluster.sh"
    r = subprocess.run([str(script), "start", str(state)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    env = {**os.environ, "SLURM_CONF": str(state / "slurm.conf")}
    try:
        yield env
    finally:
        subprocess.run([str(script), "stop", str(state)], capture_output=True)
        if os.environ.get("LUXEST_KEEP_SLURM"):
            print(f"cluster state kept in {state}")
        else:
            shutil.rmtree(state, ignore_errors=True)


def dataset_files(name):
    d = ROOT / "data" / name
    return {p.relative_to(d): p for p in d.rglob("*") if p.is_file()}


def assert_same_images(a, b):
    """Every file of dataset `a` is in `b` with equal pixels and header values (timings aside)."""
    fa, fb = dataset_files(a), dataset_files(b)
    assert sorted(fa) == sorted(fb)
    assert len(fa) > 50
    for rel in fa:
        x, y = OpenEXR.File(str(fa[rel])), OpenEXR.File(str(fb[rel]))
        hx, hy = x.header(), y.header()
        for key in (set(hx) | set(hy)) - TIMING_KEYS:
            assert str(hx.get(key)) == str(hy.get(key)), f"{rel}: header {key}"
        for c in x.channels():
            assert np.array_equal(x.channels()[c].pixels, y.channels()[c].pixels), f"{rel}: {c}"


def remove_dataset(name):
    for d in (ROOT / "data" / name, ROOT / "build" / "dataset" / name):
        shutil.rmtree(d, ignore_errors=True)


def test_dataset_through_slurm_equals_the_run_without(cluster):
    plain, slurm = "pytest-slurm-plain", "pytest-slurm-srun"
    try:
        for name in (plain, slurm):
            remove_dataset(name)
        r = make("-j2", "reference", "noisy", DATASET=plain, **TINY)
        assert r.returncode == 0, r.stderr
        launch = "srun --ntasks=1 --cpus-per-task=1 --exact --quiet"
        r = make("-j2", "reference", "noisy", env=cluster, DATASET=slurm, LAUNCH=launch, **TINY)
        assert r.returncode == 0, r.stderr
        # Every stage command ran as a job step.
        stage_lines = [l for l in r.stdout.splitlines() if any(p in l for p in stage_vars().values())]
        assert stage_lines and all(l.startswith(launch + " ") for l in stage_lines)
        assert_same_images(plain, slurm)
    finally:
        for name in (plain, slurm):
            remove_dataset(name)


def test_a_failed_step_fails_its_make_target(cluster):
    name = "pytest-slurm-fail"
    try:
        remove_dataset(name)
        r = make("reference", env=cluster, DATASET=name, LAUNCH="srun --ntasks=1 --quiet", TRACE="/bin/false", **TINY)
        assert r.returncode != 0
        assert "Error" in r.stderr
        assert not list((ROOT / "data" / name).rglob("*_ref.hdr.exr"))
    finally:
        remove_dataset(name)


def squeue(env, job):
    r = subprocess.run(["squeue", "-h", "-j", job, "-o", "%T"], capture_output=True, text=True, env=env)
    return r.stdout.strip()


def sbatch(env, log, script, *options):
    """Submits shell `script` as a one-task, one-CPU batch job logging to `log`; its job id."""
    r = subprocess.run(
        ["sbatch", "--parsable", *options, "-n1", "-c1", "-o", str(log), "--wrap", script],
        capture_output=True,
        text=True,
        env=env,
    )
    assert r.returncode == 0, r.stderr
    return r.stdout.strip().split(";")[0]


def cancel_when(env, cmd, log, ready):
    """Submits `cmd` as a batch job, cancels it (SIGTERM, then SIGKILL) as soon as `ready()`
    holds or the job has ended, and waits until Slurm has cleaned it up."""
    job = sbatch(env, log, shlex.join(cmd))
    deadline = time.time() + 120
    while not ready() and squeue(env, job):
        assert time.time() < deadline, f"job {job}: not ready in 120 s ({squeue(env, job)})"
        time.sleep(0.01)
    subprocess.run(["scancel", job], check=True, env=env)
    deadline = time.time() + 60
    while squeue(env, job):
        assert time.time() < deadline, f"job {job} still {squeue(env, job)} 60 s after scancel"
        time.sleep(0.1)


def test_a_cancelled_job_leaves_no_partial_output(cluster, tmp_path):
    # A render whose snapshots are committed together at its end, as a batch job, cancelled
    # while it renders and again the moment its files start to appear: the images under final
    # names are all of them, each whole, or none; the rerun through Slurm completes.
    scene = tmp_path / "scene.lxs"
    bins = stage_vars()
    subprocess.run(
        [bins["SCENE_COMPILE"], str(ROOT / "scenes" / "cornell-box.ron"), "-o", str(scene), "-q"], check=True
    )
    levels = [1 << k for k in range(9)]
    out = tmp_path / "out" / "cb"
    out.parent.mkdir()
    cmd = [
        bins["TRACE"],
        str(scene),
        "--spp",
        str(levels[-1]),
        "--snapshots",
        ",".join(map(str, levels[:-1])),
        "--resolution",
        "96x96",
        "--threads",
        "1",
        "-o",
        str(out),
    ]

    def finals():
        return sorted(out.parent.glob("cb_*.exr"))

    def check_all_or_nothing():
        names = [p.name for p in finals()]
        assert names in ([], sorted(contract.image_name("cb", "hdr", n) for n in levels)), names
        for p in finals():
            image = contract.read(p)
            assert contract.samples(image.header, p) == contract.parse_image_name(p.name).spp
            assert image.pixels.shape == (96, 96, 3) and np.isfinite(image.pixels).all()

    started = time.time()
    cancel_when(cluster, cmd, tmp_path / "a.log", lambda: time.time() - started > 1.0)
    assert finals() == [], "cancelled while rendering: nothing under a final name"
    cancel_when(cluster, cmd, tmp_path / "b.log", lambda: any(out.parent.iterdir()))
    check_all_or_nothing()
    r = subprocess.run(["srun", "-n1", "-c1", "--quiet", *cmd], capture_output=True, text=True, env=cluster)
    assert r.returncode == 0, r.stderr
    assert len(finals()) == len(levels)
    check_all_or_nothing()


def test_make_n_plans_the_same_commands_with_a_launcher():
    # No cluster needed: the dry run's stage commands with LAUNCH are those without it, prefixed.
    launch = "srun --ntasks=1 --cpus-per-task=8 --exact"
    targets = ("reference", "noisy", "validate", "train")
    plain = make("-n", *targets, DATASET="pytest-dry-launch", **TINY)
    launched = make("-n", *targets, DATASET="pytest-dry-launch", LAUNCH=launch, **TINY)
    assert plain.returncode == 0 and launched.returncode == 0, plain.stderr + launched.stderr
    # Lines with runs of spaces made one (an empty launcher leaves two).
    a = [" ".join(l.split()) for l in plain.stdout.splitlines() if l.strip()]
    b = [" ".join(l.split()) for l in launched.stdout.splitlines() if l.strip()]
    assert len(a) == len(b) > 20
    stage_names = {"scene-compile", "trace", "aov-write", "estimate", "denoise", "evaluate", "report"}
    prefixed = 0
    cd = "cd training && "
    for x, y in zip(a, b):
        is_stage = Path(x.split()[0]).name in stage_names
        if x.startswith(cd):  # a training step (TRAIN_LAUNCH follows LAUNCH by default)
            assert y == cd + f"{launch} " + x[len(cd) :], (x, y)
            prefixed += 1
        elif is_stage:
            assert y == f"{launch} {x}", (x, y)
            prefixed += 1
        else:
            assert y == x, (x, y)
    assert prefixed > 20 and sum(l.startswith(cd) for l in a) == 4
    remove_dataset("pytest-dry-launch")


def tiny_training_data(root):
    """The training tests' tiny preprocessed split (training/tests/conftest.py) and train.py's
    arguments for a short run of the steps schedule, checkpointing every 5 steps."""
    sys.path.insert(0, str(ROOT / "training" / "tests"))
    from conftest import make_tiny_prep

    return make_tiny_prep(root) + "--base-width 8 --schedule steps --steps 60 --minutes 30 --checkpoint-every 5".split()


def checkpoint_step(path):
    import torch

    try:
        return torch.load(path, weights_only=False)["step"]
    except (OSError, EOFError, RuntimeError, KeyError):
        return None


def test_a_requeued_training_resumes_where_it_stopped(cluster, tmp_path):
    # The same run twice: straight through, and as a batch job requeued (killed and queued
    # again, as pre-emption does) once it has checkpointed; the requeued job resumes from its
    # checkpoint and ends with the weights of the uninterrupted run.
    import torch

    args = tiny_training_data(tmp_path)
    train = [sys.executable, "train.py", *args]
    subprocess.run(
        train + ["--run-dir", str(tmp_path / "whole")], cwd=ROOT / "training", check=True, capture_output=True
    )
    cut = tmp_path / "cut"
    script = f"cd {shlex.quote(str(ROOT / 'training'))} && " + shlex.join(train + ["--run-dir", str(cut), "--resume"])
    job = sbatch(cluster, tmp_path / "job.log", script, "--requeue")
    deadline = time.time() + 300
    while not (checkpoint_step(cut / "checkpoint.pt") or 0) >= 5:
        assert time.time() < deadline, f"job {job}: no checkpoint in 300 s ({(tmp_path / 'job.log').read_text()})"
        time.sleep(0.05)
    subprocess.run(["scontrol", "requeue", job], check=True, env=cluster)
    deadline, released = time.time() + 300, False
    while "JobState=COMPLETED" not in (
        state := subprocess.run(["scontrol", "show", "job", job], capture_output=True, text=True, env=cluster).stdout
    ):
        assert "FAILED" not in state and time.time() < deadline, state + (tmp_path / "job.log").read_text()
        gone = subprocess.run(["pgrep", "-f", f"--run-dir {cut}"], capture_output=True).returncode != 0
        if not released and "Reason=BeginTime" in state and gone:
            # Slurm holds a requeued job back for about two minutes; a test need not wait that
            # long, but slurmd refuses the job for a few seconds after it killed it ("already
            # killed, do not launch batch job").
            time.sleep(5)
            subprocess.run(["scontrol", "update", f"JobId={job}", "StartTime=now"], check=True, env=cluster)
            released = True
        time.sleep(0.1)
    summary = json.loads((cut / "summary.json").read_text())
    assert summary["steps"] == 60 and len(summary["resumed_at"]) == 1 and 5 <= summary["resumed_at"][0] < 60, summary
    assert "Restarts=1" in state
    whole = torch.load(tmp_path / "whole" / "checkpoint.pt", weights_only=False)["model"]
    resumed = torch.load(cut / "checkpoint.pt", weights_only=False)["model"]
    assert whole.keys() == resumed.keys()
    for k in whole:
        assert torch.equal(whole[k], resumed[k]), k
