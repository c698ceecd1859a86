"""Denoises luxest images with Intel Open Image Denoise (the peer of `denoise` in `make eval` and
`make bench-denoise`): its "RT" filter with the HDR colour, albedo and normal inputs (`hdr =
true`), on the CPU with all cores, through its C API. Two releases:

- OIDN 1.4.3 from PyPI `oidn` (in .venv, scripts/setup-python.sh), the default, called as a new
  user calls it: default quality, the features taken as they are (`--aux noisy`);
- OIDN 2.5.1 from PyPI `pyoidn` (in .venv-peers, `scripts/setup.sh --peers`): `--oidn-lib` names
  its `libOpenImageDenoise.so.2`, loaded directly (its Python binding is not needed). Run at its
  best quality by `make eval`: `quality = high`, and the features as OIDN's documentation
  recommends for each kind — antialiased (`aov-write --min-samples`) features are noise-free
  (`--aux clean`: `cleanAux = true`); features of the snapshot's own samples are noisy and are
  denoised first by their own RT filters, albedo and normal, and then passed as clean (`--aux
  prefilter`, OIDN's highest-quality path for noisy features).

The output keeps the noisy image's header and adds what `denoise` adds
(python/luxest_contract.py, docs/architecture.md): `luxest.denoiser` = `oidn-<version>` (so
`evaluate images` labels it `<estimator>+oidn`, or `+oidn2` for release 2), `luxest.denoiseSeconds`
(wall-clock seconds of the filters' execution, prefiltering included, excluding I/O, as `denoise`
records its inference), `luxest.denoiseCpuSeconds` (the process's CPU seconds over that
execution, all threads) and `luxest.featureSeconds` (the features' render seconds); both times
are also printed, per megapixel. Bad input: one line naming the file, exit 1; the output may not
be one of the inputs and is written atomically."""

import argparse
import ctypes
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
import luxest_contract as contract  # noqa: E402

AUX_MODES = ("noisy", "clean", "prefilter")
QUALITIES = {"default": 0, "fast": 4, "balanced": 5, "high": 6}  # OIDNQuality (OIDN 2)
FLOAT3 = 3  # OIDN_FORMAT_FLOAT3


class Library:
    """One OIDN shared library through ctypes: the few C calls used, under the names of its
    release (1.x: `oidnSetFilter1b`, 2.x: `oidnSetFilterBool`, ...), and its version."""

    def __init__(self, path=None):
        if path is None:
            import oidn  # OIDN 1.4.3: the binding wraps no parameter setters, so the C API directly

            self.lib, self.version = getattr(oidn, "__lib_oidn"), oidn.oidn_version
        else:
            try:
                self.lib = ctypes.CDLL(str(path))
            except OSError as e:
                raise contract.ContractError(f"{path}: not an OIDN library that loads ({e})") from None
            if not hasattr(self.lib, "oidnSetFilterInt"):
                raise contract.ContractError(f"{path}: not an OIDN 2 library (no oidnSetFilterInt)")
            self.version = self._version(path)
        lib, p = self.lib, ctypes.c_void_p
        self.v2 = hasattr(lib, "oidnSetFilterBool")
        lib.oidnNewDevice.restype = p
        lib.oidnNewDevice.argtypes = [ctypes.c_int]
        lib.oidnCommitDevice.argtypes = [p]
        lib.oidnReleaseDevice.argtypes = [p]
        lib.oidnNewFilter.restype = p
        lib.oidnNewFilter.argtypes = [p, ctypes.c_char_p]
        lib.oidnSetSharedFilterImage.argtypes = [p, ctypes.c_char_p, p, ctypes.c_int] + [ctypes.c_size_t] * 5
        lib.oidnCommitFilter.argtypes = [p]
        lib.oidnExecuteFilter.argtypes = [p]
        lib.oidnReleaseFilter.argtypes = [p]
        lib.oidnGetDeviceError.restype = ctypes.c_int
        lib.oidnGetDeviceError.argtypes = [p, ctypes.POINTER(ctypes.c_char_p)]
        self.set_bool = lib.oidnSetFilterBool if self.v2 else lib.oidnSetFilter1b
        self.set_bool.argtypes = [p, ctypes.c_char_p, ctypes.c_bool]
        self.set_int = lib.oidnSetFilterInt if self.v2 else lib.oidnSetFilter1i
        self.set_int.argtypes = [p, ctypes.c_char_p, ctypes.c_int]
        self.set_device_int = lib.oidnSetDeviceInt if self.v2 else lib.oidnSetDevice1i
        self.set_device_int.argtypes = [p, ctypes.c_char_p, ctypes.c_int]
        get_device_int = lib.oidnGetDeviceInt if self.v2 else lib.oidnGetDevice1i
        get_device_int.restype = ctypes.c_int
        get_device_int.argtypes = [p, ctypes.c_char_p]
        self.get_device_int = get_device_int

    def _version(self, path):
        """`major.minor.patch` from the device's `version` parameter (major·10000 + minor·100 +
        patch)."""
        lib = self.lib
        lib.oidnNewDevice.restype = ctypes.c_void_p
        lib.oidnGetDeviceInt.restype = ctypes.c_int
        lib.oidnGetDeviceInt.argtypes = [ctypes.c_void_p, ctypes.c_char_p]
        lib.oidnReleaseDevice.argtypes = [ctypes.c_void_p]
        device = lib.oidnNewDevice(1)  # OIDN_DEVICE_TYPE_CPU
        if not device:
            raise contract.ContractError(f"{path}: OIDN found no CPU device")
        v = lib.oidnGetDeviceInt(ctypes.c_void_p(device), b"version")
        lib.oidnReleaseDevice(ctypes.c_void_p(device))
        return f"{v // 10000}.{v // 100 % 100}.{v % 100}"

    def check(self, device):
        message = ctypes.c_char_p()
        err = self.lib.oidnGetDeviceError(device, ctypes.byref(message))
        if err:
            raise RuntimeError(f"OIDN {self.version} error {err}: {(message.value or b'').decode()}")


def oidn_filter(color, albedo, normal, threads=0, lib=None, quality="default", aux="noisy"):
    """OIDN's RT filter on float32 (H, W, 3) arrays (HDR colour) with the library `lib` (a
    Library; OIDN 1.4.3 when None), at `quality` (OIDN 2 only), the features taken as `aux`
    (AUX_MODES: `noisy` as they are, `clean` with cleanAux, `prefilter` denoised by their own RT
    filters first, then clean); returns (output, wall seconds, CPU seconds of the process during
    the execution of every filter)."""
    lib = lib or Library()
    if aux not in AUX_MODES:
        raise ValueError(f"aux {aux!r}: expected one of {AUX_MODES}")
    if quality != "default" and not lib.v2:
        raise ValueError(f"quality {quality!r}: OIDN {lib.version} has no quality setting")
    c = lib.lib
    h, w, _ = color.shape
    color, albedo, normal = (np.ascontiguousarray(a, dtype=np.float32) for a in (color, albedo, normal))
    if aux == "prefilter":  # denoised in place of copies; the inputs stay as they were
        albedo, normal = albedo.copy(), normal.copy()
    out = np.zeros_like(color)
    device = ctypes.c_void_p(c.oidnNewDevice(1))  # OIDN_DEVICE_TYPE_CPU
    if threads:
        lib.set_device_int(device, b"numThreads", threads)
    c.oidnCommitDevice(device)
    lib.check(device)

    def new_filter(images, flags):
        f = ctypes.c_void_p(c.oidnNewFilter(device, b"RT"))
        for name, data in images:
            c.oidnSetSharedFilterImage(f, name, data.ctypes.data, FLOAT3, w, h, 0, 0, 0)
        for name, value in flags:
            lib.set_bool(f, name, value)
        if lib.v2:
            lib.set_int(f, b"quality", QUALITIES[quality])
        c.oidnCommitFilter(f)
        lib.check(device)
        return f

    filters = []
    if aux == "prefilter":
        filters += [
            new_filter([(name, a), (b"output", a)], []) for name, a in ((b"albedo", albedo), (b"normal", normal))
        ]
    images = [(b"color", color), (b"albedo", albedo), (b"normal", normal), (b"output", out)]
    filters.append(new_filter(images, [(b"hdr", True)] + ([(b"cleanAux", True)] if aux != "noisy" else [])))
    wall0, cpu0 = time.perf_counter(), time.process_time()
    for f in filters:
        c.oidnExecuteFilter(f)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    try:
        lib.check(device)
    finally:
        for f in filters:
            c.oidnReleaseFilter(f)
        c.oidnReleaseDevice(device)
    return out, wall, cpu


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("noisy", help="noisy image (.hdr.exr)")
    ap.add_argument("--alb", required=True, help="albedo feature (.alb.exr)")
    ap.add_argument("--nrm", required=True, help="normal feature (.nrm.exr)")
    ap.add_argument("-o", "--out", required=True, help="denoised image (.exr)")
    ap.add_argument("--threads", type=int, default=0, help="OIDN threads (0: all cores)")
    ap.add_argument(
        "--oidn-lib",
        help="an OIDN 2 shared library (libOpenImageDenoise.so.2 of .venv-peers' pyoidn); default: OIDN 1.4.3 of PyPI oidn",
    )
    ap.add_argument("--quality", choices=sorted(QUALITIES), default="default", help="filter quality (OIDN 2)")
    ap.add_argument(
        "--aux",
        choices=AUX_MODES,
        default="noisy",
        help="the features: as they are (noisy), noise-free (clean: cleanAux), or denoised first (prefilter)",
    )
    a = ap.parse_args(argv)
    if a.oidn_lib and not Path(a.oidn_lib).is_file():
        sys.exit(f"error: {a.oidn_lib}: no such library (scripts/setup.sh --peers installs OIDN 2.5.1)")
    try:
        lib = Library(a.oidn_lib)
    except contract.ContractError as e:
        sys.exit(f"error: {e}")
    if a.quality != "default" and not lib.v2:
        sys.exit(f"error: --quality {a.quality}: OIDN {lib.version} has no quality setting (OIDN 2 has)")

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
    out, wall, cpu = oidn_filter(noisy.pixels, feats[0].pixels, feats[1].pixels, a.threads, lib, a.quality, a.aux)
    header = dict(noisy.header)
    header[contract.DENOISER] = f"{contract.OIDN_DENOISER_PREFIX}{lib.version}"
    header[contract.DENOISE_SECONDS] = repr(wall)
    header[contract.DENOISE_CPU_SECONDS] = repr(cpu)
    header[contract.FEATURE_SECONDS] = repr(feature_seconds)
    contract.write(a.out, out, header)
    mp = noisy.pixels.shape[0] * noisy.pixels.shape[1] / 1e6
    print(
        f"oidn {lib.version}: {a.out} ({noisy.pixels.shape[1]}x{noisy.pixels.shape[0]}, {1e3 * wall / mp:.1f} ms/megapixel, "
        f"{cpu / mp:.3f} CPU-s/megapixel)",
        file=sys.stderr,
    )


if __name__ == "__main__":
    main()
