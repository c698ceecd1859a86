"""The machine a peer benchmark ran on, for its report (standard library only): the peers'
speed depends on the CPU's vector width (Mitsuba's LLVM backend compiles its wavefront for 16
lanes with AVX-512 and 8 with AVX2; OIDN picks its kernels the same way), luxest's much less."""

import os


def host_summary(cpuinfo="/proc/cpuinfo"):
    """CPU model, CPU count and widest vector extension, from `cpuinfo`."""
    model, flags, cpus = "unknown CPU", set(), os.cpu_count()
    try:
        for line in open(cpuinfo):
            key, _, value = line.partition(":")
            if key.strip() == "model name":
                model = value.strip()
            elif key.strip() == "flags":
                flags = set(value.split())
    except OSError:
        pass
    simd = "AVX-512" if "avx512f" in flags else "AVX2 (no AVX-512)" if "avx2" in flags else "no AVX2"
    return f"{model}, {cpus} CPUs, {simd}"
