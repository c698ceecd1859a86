#!/usr/bin/env bash
# Sets up everything luxest needs on a Debian machine. Idempotent: a second run only checks.
#
#   - Debian packages: libembree-dev (Embree 3.13, used through the `embree` crate), pkg-config,
#     make, gcc, python3 + pip (to fetch the onnxruntime library); chromium-headless-shell
#     (Debian's headless Chromium, /usr/bin/chromium-headless-shell: the report crate's test
#     renders report.html with it and checks the screenshot);
#   - the ONNX Runtime shared library, from the PyPI onnxruntime==1.31.* wheel, unpacked to
#     $LUXEST_ORT_DIR (default ~/.cache/luxest/onnxruntime); stages find it through
#     ORT_DYLIB_PATH or that default path;
#   - a Rust toolchain must already be installed (cargo on PATH, Rust >= 1.85).
#
#   - the Python environment of training/ in .venv (scripts/setup-python.sh: torch for CPU,
#     onnx, onnxruntime, pytest; ~4 GB).
#   - with --peers: the optional peer programs in .venv-peers (PyPI pyradiance, which bundles the
#     Radiance binaries ies2rad, oconv, rtrace, ~40 MB, used by `make lighting-radiance`; PyPI
#     mitsuba 3 with Debian's libllvm19 for its llvm_ad_rgb variant, which renders
#     `scene-compile --export-mitsuba` scenes, used by `make mitsuba-check`; PyPI pyoidn 2.5.1,
#     which ships Intel Open Image Denoise 2.5.1's shared libraries, the denoiser peer of `make
#     eval` and `make bench-denoise` beside OIDN 1.4.3 of .venv: pipelines/oidn_denoise.py loads
#     the library from there).
#
# Usage: scripts/setup.sh [--no-ort] [--no-python] [--peers]
set -euo pipefail

want_ort=1
want_python=1
want_peers=0
for a in "$@"; do
    case "$a" in
        --no-ort) want_ort=0 ;;
        --no-python) want_python=0 ;;
        --peers) want_peers=1 ;;
        *) echo "usage: $0 [--no-ort] [--no-python] [--peers]" >&2; exit 2 ;;
    esac
done

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi

missing=()
# Slurm and munge: the real single-node cluster of make test-slurm (scripts/slurm-cluster.sh).
# chromium-headless-shell: the real browser that renders the lighting report in a test.
for pkg in libembree-dev pkg-config make gcc python3 python3-pip python3-venv slurmctld slurmd slurm-client munge chromium-headless-shell; do
    if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$pkg")
    fi
done
if [ "${#missing[@]}" -gt 0 ]; then
    echo "setup: installing Debian packages: ${missing[*]}" >&2
    "${sudo_cmd[@]}" apt-get update -qq
    DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null 2>&1; then
    echo "error: cargo not found: install a Rust toolchain (>= 1.85) first, e.g. with rustup" >&2
    exit 1
fi

if [ "$want_ort" -eq 1 ]; then
    ort_dir="${LUXEST_ORT_DIR:-$HOME/.cache/luxest/onnxruntime}"
    if ! ls "$ort_dir"/libonnxruntime.so.1.31.* >/dev/null 2>&1; then
        echo "setup: fetching the ONNX Runtime 1.31 library into $ort_dir" >&2
        tmp="$(mktemp -d)"
        trap 'rm -rf "$tmp"' EXIT
        python3 -m pip download --quiet --no-deps --only-binary=:all: \
            --platform manylinux_2_28_x86_64 --python-version 3.11 \
            -d "$tmp" "onnxruntime==1.31.*"
        mkdir -p "$ort_dir"
        python3 - "$tmp" "$ort_dir" <<'PY'
import glob, os, shutil, sys, zipfile
tmp, dest = sys.argv[1], sys.argv[2]
wheel = glob.glob(os.path.join(tmp, "onnxruntime-*.whl"))[0]
with zipfile.ZipFile(wheel) as z:
    for name in z.namelist():
        base = os.path.basename(name)
        if base.startswith("libonnxruntime"):
            with z.open(name) as src, open(os.path.join(dest, base + ".part"), "wb") as dst:
                shutil.copyfileobj(src, dst)
            os.replace(os.path.join(dest, base + ".part"), os.path.join(dest, base))
PY
        lib="$(ls "$ort_dir"/libonnxruntime.so.1.31.* | head -n1)"
        ln -sf "$(basename "$lib")" "$ort_dir/libonnxruntime.so"
    fi
fi
if [ "$want_python" -eq 1 ]; then
    "$(dirname "$0")/setup-python.sh"
fi
if [ "$want_peers" -eq 1 ]; then
    # Mitsuba 3's llvm_ad_rgb variant (the fast one, the benchmark's peer) loads libLLVM 19.
    if ! dpkg-query -W -f='${Status}' libllvm19 2>/dev/null | grep -q "install ok installed"; then
        echo "setup: installing Debian package libllvm19 (Mitsuba 3's LLVM variant)" >&2
        "${sudo_cmd[@]}" apt-get update -qq
        DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends libllvm19 >/dev/null
    fi
    peers="$(cd "$(dirname "$0")/.." && pwd)/.venv-peers"
    if ! "$peers/bin/python" -c "import pyradiance, mitsuba" >/dev/null 2>&1; then
        echo "setup: creating $peers with pyradiance (Radiance binaries) and mitsuba 3" >&2
        python3 -m venv "$peers"
        "$peers/bin/pip" install --quiet "pyradiance==1.3.*" "mitsuba==3.9.*"
    fi
    if ! "$peers/bin/python" -c "import pyoidn.version as v, sys; sys.exit(v.oidn_version != '2.5.1')" >/dev/null 2>&1; then
        echo "setup: installing pyoidn 2.5.1 (Intel Open Image Denoise 2.5.1) into $peers" >&2
        "$peers/bin/pip" install --quiet "pyoidn==2.5.1.*"
    fi
fi
echo "setup: ok" >&2
