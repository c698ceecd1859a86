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


# OIDN 2.5.1: the library of PyPI pyoidn in .venv-peers (scripts/setup.sh --peers), loaded by
# oidn_denoise.py --oidn-lib; the tests that need it are skipped where it is not installed.
OIDN2_LIB = next(
    iter(sorted(ROOT.glob(".venv-peers/lib/python3*/site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2"))), None
)


def flat_wall(tmp_path):
    noisy, alb, nrm = (tmp_path / n for n in ("w_000004spp.hdr.exr", "w_000004spp.alb.exr", "w_000004spp.nrm.exr"))
    head = {contract.ESTIMATOR: "path-tracing", contract.SAMPLES: 4, contract.SEED: 3, contract.SECONDS: 0.5}
    write(noisy, [0.5, 0.4, 0.3], head)
    write(alb, [0.7, 0.7, 0.7], {**head, contract.SECONDS: 0.25})
    write(nrm, [0.0, 0.0, 1.0], {**head, contract.SECONDS: 0.125})
    return noisy, alb, nrm


def test_oidn2_at_high_quality_keeps_a_noiseless_image_with_every_kind_of_features(tmp_path):
    if OIDN2_LIB is None:
        import pytest

        pytest.skip("OIDN 2.5.1 is not installed (scripts/setup.sh --peers)")
    # As OIDN 1.4.3 above: a flat wall with exact features comes back (per-channel mean within 1 %,
    # the interior within 2 %), whether the features are passed as they are, as clean, or
    # prefiltered; the header names release 2.5.1 (evaluate labels it +oidn2), and prefiltering
    # leaves the feature files as they were.
    noisy, alb, nrm = flat_wall(tmp_path)
    before = contract.read(alb).pixels.copy()
    for aux in ("noisy", "clean", "prefilter"):
        out = tmp_path / f"{aux}.dn.exr"
        r = subprocess.run(
            [sys.executable, SCRIPT, "--oidn-lib", OIDN2_LIB, "--quality", "high", "--aux", aux, noisy]
            + ["--alb", alb, "--nrm", nrm, "-o", out],
            capture_output=True,
            text=True,
        )
        assert r.returncode == 0, r.stderr
        img = contract.read(out)
        rel = img.pixels / np.array([0.5, 0.4, 0.3]) - 1
        assert np.abs(rel.mean(axis=(0, 1))).max() < 0.01, (aux, rel.mean(axis=(0, 1)))
        assert np.abs(rel[8:-8, 8:-8]).max() < 0.02, (aux, np.abs(rel[8:-8, 8:-8]).max())
        assert img.value(contract.DENOISER) == contract.OIDN_DENOISER_PREFIX + "2.5.1"
        assert contract.estimator_label("path-tracing", img.value(contract.DENOISER)) == "path-tracing+oidn2"
        assert img.value(contract.DENOISE_SECONDS) > 0 and img.value(contract.FEATURE_SECONDS) == 0.25
    assert np.array_equal(contract.read(alb).pixels, before)


def test_oidn_options_of_release_2_are_refused_with_one_line(tmp_path):
    noisy, alb, nrm = flat_wall(tmp_path)
    base = [sys.executable, SCRIPT, noisy, "--alb", alb, "--nrm", nrm, "-o", tmp_path / "o.exr"]
    # OIDN 1.4.3 has no quality setting; a library that is not there is named.
    r = subprocess.run(base + ["--quality", "high"], capture_output=True, text=True)
    assert r.returncode == 1 and "OIDN 1.4.3 has no quality setting" in r.stderr and len(r.stderr.splitlines()) == 1
    missing = tmp_path / "libOpenImageDenoise.so.2"
    r = subprocess.run(base + ["--oidn-lib", missing], capture_output=True, text=True)
    assert r.returncode == 1 and str(missing) in r.stderr and len(r.stderr.splitlines()) == 1
    missing.write_bytes(b"not a library")
    r = subprocess.run(base + ["--oidn-lib", missing], capture_output=True, text=True)
    assert r.returncode == 1 and str(missing) in r.stderr and len(r.stderr.splitlines()) == 1
    assert not (tmp_path / "o.exr").exists()
