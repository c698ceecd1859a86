"""Denoises luxest images with Intel Open Image Denoise (the peer of `denoise` in `make eval`):
OIDN 1.4.3 from PyPI `oidn` (installed into .venv by scripts/setup-python.sh), its "RT" filter
with the HDR colour, albedo and normal inputs (`hdr = true`), on the CPU with all cores, as a new
user would call it through its C API.

The output keeps the noisy image's header and adds what `denoise` adds
(python/luxest_contract.py, docs/architecture.md): `luxest.denoiser` = `oidn-<version>` (so
`evaluate images` labels it `<estimator>+oidn`), `luxest.denoiseSeconds` (wall-clock seconds of
the filter's execution, excluding I/O, as `denoise` records its inference),
`luxest.denoiseCpuSeconds` (the process's CPU seconds over that execution, all threads) and
`luxest.featureSeconds` (the features' render seconds); both times are also printed, per
megapixel. Bad input: one line naming the file, exit 1;
the output may not be one of the inputs and is written atomically."""

import argparse
import ctypes
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
import luxest_contract as contract  # noqa: E402


def oidn_filter(color, albedo, normal, threads=0):
    """OIDN's RT filter on float32 (H, W, 3) arrays (HDR colour); returns (output, wall seconds,
    CPU seconds of the process during execution)."""
    import oidn

    lib = getattr(oidn, "__lib_oidn")  # the binding wraps no parameter setters: the C API directly
    lib.oidnSetFilter1b.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_bool]
    lib.oidnSetDevice1i.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int]
    lib.oidnGetDeviceError.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_char_p)]
    h, w, _ = color.shape
    out = np.zeros_like(color)
    device = oidn.NewDevice(oidn.DEVICE_TYPE_CPU)
    if threads:
        lib.oidnSetDevice1i(device, b"numThreads", threads)
    oidn.CommitDevice(device)
    filt = oidn.NewFilter(device, "RT")
    inputs = [np.ascontiguousarray(a, dtype=np.float32) for a in (color, albedo, normal)]
    for name, data in zip(("color", "albedo", "normal"), inputs):
        oidn.SetSharedFilterImage(filt, name, data, oidn.FORMAT_FLOAT3, w, h)
    oidn.SetSharedFilterImage(filt, "output", out, oidn.FORMAT_FLOAT3, w, h)
    lib.oidnSetFilter1b(filt, b"hdr", True)
    oidn.CommitFilter(filt)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    oidn.ExecuteFilter(filt)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    message = ctypes.c_char_p()
    err = lib.oidnGetDeviceError(device, ctypes.byref(message))
    oidn.ReleaseFilter(filt)
    oidn.ReleaseDevice(device)
    if err:
        raise RuntimeError(f"OIDN error {err}: {(message.value or b'').decode()}")
    return out, wall, cpu


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("noisy", help="noisy image (.hdr.exr)")
    ap.add_argument("--alb", required=True, help="albedo feature (.alb.exr)")
    ap.add_argument("--nrm", required=True, help="normal feature (.nrm.exr)")
    ap.add_argument("-o", "--out", required=True, help="denoised image (.exr)")
    ap.add_argument("--threads", type=int, default=0, help="OIDN threads (0: all cores)")
    a = ap.parse_args(argv)
    import oidn

    ins = [Path(p).resolve() for p in (a.noisy, a.alb, a.nrm)]
    if Path(a.out).resolve() in ins:
        sys.exit(f"error: {a.out}: the output may not be one of the inputs")
    try:
        noisy = contract.read(a.noisy)
        feats = [contract.read(p) for p in (a.alb, a.nrm)]
        for f in feats:
            if f.pixels.shape != noisy.pixels.shape:
                raise contract.ContractError(
                    f"{f.path}: {f.pixels.shape[1]}x{f.pixels.shape[0]}, the noisy image "
                    f"is {noisy.pixels.shape[1]}x{noisy.pixels.shape[0]}"
                )
        if not np.isfinite(noisy.pixels).all():
            raise contract.ContractError(f"{a.noisy}: pixels that are not finite")
        feature_seconds = max(f.value(contract.SECONDS) or 0.0 for f in feats)
    except contract.ContractError as e:
        sys.exit(f"error: {e}")
    out, wall, cpu = oidn_filter(noisy.pixels, feats[0].pixels, feats[1].pixels, a.threads)
    header = dict(noisy.header)
    header[contract.DENOISER] = f"{contract.OIDN_DENOISER_PREFIX}{oidn.oidn_version}"
    header[contract.DENOISE_SECONDS] = repr(wall)
    header[contract.DENOISE_CPU_SECONDS] = repr(cpu)
    header[contract.FEATURE_SECONDS] = repr(feature_seconds)
    contract.write(a.out, out, header)
    mp = noisy.pixels.shape[0] * noisy.pixels.shape[1] / 1e6
    print(
        f"oidn: {a.out} ({noisy.pixels.shape[1]}x{noisy.pixels.shape[0]}, {1e3 * wall / mp:.1f} ms/megapixel, "
        f"{cpu / mp:.3f} CPU-s/megapixel)",
        file=sys.stderr,
    )


if __name__ == "__main__":
    main()
