"""training/compare_image.py: a model and, with --oidn, Intel Open Image Denoise scored on a split
by the evaluate stage, per level and per scene, with luxest's margin over OIDN."""

import json
import math
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import compare_image  # noqa: E402
import luxest_contract as contract  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
TINY = ROOT / "tests" / "fixtures" / "denoise" / "tiny.onnx"

# A stand-in for `evaluate images` (the Rust stage is built after pytest runs in make test): one
# row per test image with the PSNR of its raw pixels against the reference's (peak 1), so the test
# can recompute every number independently.
FAKE_EVALUATE = textwrap.dedent(f"""\
    import csv, sys
    import numpy as np
    sys.path.insert(0, {str(ROOT / "python")!r})
    import luxest_contract as contract
    a = sys.argv[1:]
    assert a[0] == "images" and a[1] == "--reference"
    ref = contract.read(a[2]).pixels.astype(np.float64)
    out = a[a.index("-o") + 1]
    with open(out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["image", "psnr_db", "ssim"])
        for t in a[3:a.index("-o")]:
            x = contract.read(t).pixels.astype(np.float64)
            w.writerow([t, repr(float(-10 * np.log10(np.mean((x - ref) ** 2)))), repr(float(1 - np.mean(np.abs(x - ref))))])
    """)


def psnr(path, ref):
    x, r = (contract.read(p).pixels.astype(np.float64) for p in (path, ref))
    return -10 * math.log10(float(np.mean((x - r) ** 2)))


def make_split(root, rng):
    """Two scenes of a lit wall with a step, noisy at 1 and 4 spp (seed 1), references of seed 2."""
    split = root / "split"
    split.mkdir()
    for name in ("a", "b"):
        clean = np.full((48, 64, 3), 0.4, np.float32)
        clean[:, 32:] = 0.8
        contract.write(split / contract.image_name(name, "hdr"), clean, {contract.SAMPLES: 1024, contract.SEED: 2})
        for spp in (1, 4):
            head = {contract.SAMPLES: spp, contract.SEED: 1, contract.ESTIMATOR: "path-tracing", contract.SECONDS: 0.1}
            noisy = clean * rng.gamma(4.0 * spp, 1 / (4.0 * spp), clean.shape).astype(np.float32)
            contract.write(split / contract.image_name(name, "hdr", spp), noisy, head)
            contract.write(split / contract.image_name(name, "alb", spp), np.full_like(clean, 0.7), head)
            normal = np.zeros_like(clean)
            normal[..., 2] = 1
            contract.write(split / contract.image_name(name, "nrm", spp), normal, head)
    return split


def test_model_and_oidn_scored_per_level_and_scene(tmp_path):
    pytest.importorskip("oidn")
    split = make_split(tmp_path, np.random.default_rng(5))
    fake = tmp_path / "evaluate"
    fake.write_text(f"#!{sys.executable}\n" + FAKE_EVALUATE)
    fake.chmod(0o755)
    work = tmp_path / "work"
    out_json = tmp_path / "m.json"
    compare_image.main(
        [
            "--model",
            str(TINY),
            "--split-dir",
            str(split),
            "--work-dir",
            str(work),
            "--evaluate",
            str(fake),
            "--spp",
            "1",
            "4",
            "--oidn",
            "--json",
            str(out_json),
        ]
    )
    m = json.loads(out_json.read_text())
    for spp in (1, 4):
        level = m["levels"][str(spp)]
        assert level["scenes"] == 2
        want = {"psnr_noisy": [], "psnr_denoised": [], "psnr_oidn": []}
        for name in ("a", "b"):
            ref = split / contract.image_name(name, "hdr")
            noisy = split / contract.image_name(name, "hdr", spp)
            dn = work / contract.image_name(name, "dn", spp)
            peer = work / "oidn" / contract.image_name(name, "dn", spp)
            assert contract.read(peer).value(contract.DENOISER).startswith(contract.OIDN_DENOISER_PREFIX)
            scene = m["scenes"][name][str(spp)]
            for key, path in (("psnr_noisy", noisy), ("psnr_denoised", dn), ("psnr_oidn", peer)):
                assert scene[key] == pytest.approx(psnr(path, ref), abs=1e-9)
                want[key].append(psnr(path, ref))
        for key, vals in want.items():
            assert level[key] == pytest.approx(sum(vals) / 2, abs=1e-9)
        # OIDN removes most of the noise of a flat wall: far above its input.
        assert level["psnr_oidn"] > level["psnr_noisy"] + 6


def test_a_split_without_references_is_one_line(tmp_path, capsys):
    split = make_split(tmp_path, np.random.default_rng(6))
    (split / contract.image_name("a", "hdr")).unlink()
    (split / contract.image_name("b", "hdr")).unlink()
    with pytest.raises(SystemExit) as e:
        compare_image.main(
            [
                "--model",
                str(TINY),
                "--split-dir",
                str(split),
                "--work-dir",
                str(tmp_path / "w"),
                "--evaluate",
                "/bin/false",
                "--spp",
                "1",
            ]
        )
    assert "compare_image: error:" in str(e.value) and "reference" in str(e.value)
