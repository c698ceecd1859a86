"""pipelines/bench_denoise.py: the CPU seconds per megapixel it reports are those its denoisers
spend per megapixel, whatever they spend per call."""

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python"))
import luxest_contract as contract  # noqa: E402

BENCH = ROOT / "pipelines" / "bench_denoise.py"

# A stand-in denoiser: reads its input's size from the EXR header, burns `fixed` CPU seconds
# plus `per_mp` per megapixel of it, and writes a placeholder output (the command line of
# `denoise` or of oidn_denoise.py). No imports beyond the standard library, so that its start-up
# costs little and varies little.
FAKE = textwrap.dedent("""
    import struct, sys, time
    fixed, per_mp, hdr = float(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
    out = sys.argv[sys.argv.index("-o") + 1]
    head = open(hdr, "rb").read(4096)
    i = head.index(b"dataWindow\\0box2i\\0") + len(b"dataWindow\\0box2i\\0") + 4
    x0, y0, x1, y1 = struct.unpack("<4i", head[i:i + 16])
    budget = fixed + per_mp * (x1 - x0 + 1) * (y1 - y0 + 1) / 1e6
    t = time.process_time()
    while time.process_time() - t < budget:
        pass
    open(out, "wb").write(b"placeholder")
""")


def scene(tmp_path, kinds=("hdr", "alb", "nrm", "emi", "ema")):
    rng = np.random.default_rng(2)
    for kind in kinds:
        contract.write(
            tmp_path / contract.image_name("cb", kind, 16),
            rng.random((64, 64, 3)),
            {contract.SAMPLES: 16, contract.SEED: 1},
        )
    return tmp_path / contract.image_name("cb", "hdr", 16)


def bench(tmp_path, hdr, luxest, peer, *extra):
    fake = tmp_path / "fake.py"
    fake.write_text(FAKE)
    cmd = lambda fixed, per_mp: f"{sys.executable} {fake} {fixed} {per_mp}"
    return subprocess.run(
        [
            sys.executable,
            str(BENCH),
            "--input",
            str(hdr),
            "--model",
            "m.onnx",
            "--denoise",
            cmd(*luxest),
            "--oidn",
            cmd(*peer),
            "--side",
            "256",
            "--rounds",
            "3",
            "--work-dir",
            str(tmp_path / "work"),
            "-o",
            str(tmp_path / "out" / "bench.md"),
            *extra,
        ],
        capture_output=True,
        text=True,
    )


def test_the_marginal_cost_per_megapixel_is_the_denoisers_own(tmp_path):
    # 4.0 and 2.0 CPU-s per megapixel, with per-call costs (0.15 / 0.06 s) that must cancel (not
    # cancelled, they would read 6.3 and 2.9). The tolerance covers the spread of a Python
    # process's start-up CPU time (a few ms) over the 0.061 megapixels between the two sizes
    # (64² and 256²): the medians of 3 rounds differ by 0.24 and 0.12 CPU-s.
    hdr = scene(tmp_path)
    (tmp_path / "out").mkdir()
    # A further peer (--peer NAME=COMMAND, as OIDN 2.5.1 in make bench-denoise): 8.0 CPU-s per
    # megapixel, its own row and ratio, in the same rounds.
    fake = tmp_path / "fake.py"
    r = bench(tmp_path, hdr, (0.15, 4.0), (0.06, 2.0), "--peer", f"oidn2={sys.executable} {fake} 0.03 8.0")
    assert r.returncode == 0, r.stderr
    rows = {row["denoiser"]: row for row in contract._read_csv(tmp_path / "out" / "bench.csv")}
    assert float(rows["luxest"]["cpu_s_per_megapixel"]) == pytest.approx(4.0, rel=0.25)
    assert float(rows["oidn"]["cpu_s_per_megapixel"]) == pytest.approx(2.0, rel=0.25)
    assert float(rows["oidn2"]["cpu_s_per_megapixel"]) == pytest.approx(8.0, rel=0.25)
    # The per-call cost shows in the small image's seconds, not in the per-megapixel ones.
    assert float(rows["luxest"]["cpu_s_small"]) > float(rows["oidn"]["cpu_s_small"]) + 0.05
    table = (tmp_path / "out" / "bench.md").read_text()
    assert "OIDN 1.4.3 (peer)" in table
    ratio = float(table.split("luxest / OIDN, CPU-s per megapixel: ")[1].split()[0])
    assert ratio == pytest.approx(2.0, rel=0.25)
    assert "| oidn2 (peer) |" in table
    assert float(table.split("luxest / oidn2, CPU-s per megapixel: ")[1].split()[0]) == pytest.approx(0.5, rel=0.25)


def test_bad_input_one_line_and_nothing_written(tmp_path):
    hdr = scene(tmp_path, kinds=("hdr", "alb", "nrm"))  # no emission features
    (tmp_path / "out").mkdir()
    r = bench(tmp_path, hdr, (0, 0), (0, 0))
    assert r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1
    assert "cb_000016spp.emi.exr: missing" in r.stderr
    assert not (tmp_path / "out" / "bench.md").exists()
    r = bench(tmp_path, hdr, (0, 0), (0, 0), "--features", "alb,nrm", "--denoise", "/no/such/denoiser")
    assert (
        r.returncode == 1
        and r.stderr.strip() == "bench_denoise: error: /no/such/denoiser: cannot run it (No such file or directory)"
    )
    assert not list((tmp_path / "out").iterdir())
    r = bench(tmp_path, hdr, (0, 0), (0, 0), "--features", "alb,nrm", "-o", str(tmp_path / "out" / "bench.csv"))
    assert r.returncode == 1 and "the Markdown table's name" in r.stderr
    # An input inside the work directory's copies would be overwritten by them.
    (tmp_path / "work" / "small").mkdir(parents=True, exist_ok=True)
    inside = scene(tmp_path / "work" / "small")
    r = bench(tmp_path, inside, (0, 0), (0, 0))
    assert r.returncode == 1 and "inside the work directory" in r.stderr
    assert not list((tmp_path / "out").iterdir())
