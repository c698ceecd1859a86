"""pipelines/oidn_denoise.py, the peer denoiser of `make eval`: Intel Open Image Denoise through
PyPI `oidn`, writing luxest's header contract."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

import luxest_contract as contract

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "pipelines" / "oidn_denoise.py"


def write(path, value, header):
    contract.write(path, np.broadcast_to(np.asarray(value, np.float32), (48, 64, 3)), header)


def test_oidn_keeps_a_noiseless_image_and_records_the_contract(tmp_path):
    # A flat wall with exact features has nothing to remove: OIDN returns it, per channel mean
    # within 1 % and every pixel 8 or more from the border within 2 % (its network is not the
    # identity; at the border it strays by up to 12 %), and the header says who denoised it, how
    # long it took and what the features cost.
    noisy, alb, nrm, out = (
        tmp_path / n
        for n in ("w_000004spp.hdr.exr", "w_000004spp.alb.exr", "w_000004spp.nrm.exr", "w_000004spp.dn.exr")
    )
    head = {contract.ESTIMATOR: "path-tracing", contract.SAMPLES: 4, contract.SEED: 3, contract.SECONDS: 0.5}
    write(noisy, [0.5, 0.4, 0.3], head)
    write(alb, [0.7, 0.7, 0.7], {**head, contract.SECONDS: 0.25})
    write(nrm, [0.0, 0.0, 1.0], {**head, contract.SECONDS: 0.125})
    subprocess.run(
        [sys.executable, SCRIPT, noisy, "--alb", alb, "--nrm", nrm, "-o", out], check=True, capture_output=True
    )
    img = contract.read(out)
    rel = img.pixels / np.array([0.5, 0.4, 0.3]) - 1
    assert np.abs(rel.mean(axis=(0, 1))).max() < 0.01, rel.mean(axis=(0, 1))
    assert np.abs(rel[8:-8, 8:-8]).max() < 0.02, np.abs(rel[8:-8, 8:-8]).max()
    assert img.value(contract.DENOISER).startswith(contract.OIDN_DENOISER_PREFIX)
    assert img.value(contract.DENOISE_SECONDS) > 0
    wall, cpu = img.value(contract.DENOISE_SECONDS), img.value(contract.DENOISE_CPU_SECONDS)
    assert 0 < cpu <= len(os.sched_getaffinity(0)) * wall * 1.1 + 0.01, (cpu, wall)  # CPU seconds, all threads
    assert img.value(contract.FEATURE_SECONDS) == 0.25
    assert img.value(contract.SAMPLES) == 4 and img.value(contract.ESTIMATOR) == "path-tracing"


def test_oidn_refuses_mismatched_features_and_overwriting_an_input(tmp_path):
    noisy, alb, nrm = (tmp_path / n for n in ("a.hdr.exr", "a.alb.exr", "a.nrm.exr"))
    write(noisy, 0.5, {contract.SECONDS: 1.0})
    contract.write(alb, np.zeros((8, 8, 3), np.float32), {contract.SECONDS: 1.0})  # the image is 64x48
    write(nrm, [0, 0, 1], {contract.SECONDS: 1.0})
    r = subprocess.run(
        [sys.executable, SCRIPT, noisy, "--alb", alb, "--nrm", nrm, "-o", tmp_path / "o.exr"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 1 and str(alb) in r.stderr and "8x8" in r.stderr and not (tmp_path / "o.exr").exists()
    r = subprocess.run(
        [sys.executable, SCRIPT, noisy, "--alb", nrm, "--nrm", nrm, "-o", noisy], capture_output=True, text=True
    )
    assert r.returncode == 1 and "one of the inputs" in r.stderr
