"""pipelines/host.py: the peer benchmarks (bench_pt, bench_sensors, bench_denoise) name the host's
CPU and vector width in their reports: the peers' speed depends on it."""

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "pipelines"))
import host  # noqa: E402

CPUINFO = """processor\t: 0
model name\t: AMD EPYC 9B14
flags\t\t: fpu sse2 avx fma avx2 {extra}

processor\t: 1
model name\t: AMD EPYC 9B14
flags\t\t: fpu sse2 avx fma avx2 {extra}
"""


def test_host_summary_names_the_cpu_and_its_widest_vectors(tmp_path):
    cases = {"avx512f avx512bw": "AVX-512", "": "AVX2 (no AVX-512)"}
    for extra, simd in cases.items():
        info = tmp_path / "cpuinfo"
        info.write_text(CPUINFO.format(extra=extra))
        assert host.host_summary(info) == f"AMD EPYC 9B14, {os.cpu_count()} CPUs, {simd}"
    assert host.host_summary(tmp_path / "missing").startswith("unknown CPU")
