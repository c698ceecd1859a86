#!/usr/bin/env bash
# Sets up the Python environment of training/ in .venv (ignored by git). Idempotent.
#
# The PyPI torch wheel is a CUDA build: it will not import without the NVIDIA libraries it
# preloads, and its declared dependencies pull ~5 GB (cuda-toolkit, triton, ...). The smallest
# set that imports and trains on CPU: torch with --no-deps plus 11 NVIDIA library wheels with
# --no-deps (cuBLAS, CUDA runtime, NVRTC, CUPTI, cuFFT, cuFile, cuSPARSE, cuDNN, cuSPARSELt,
# NCCL, NVSHMEM; cuSOLVER, nvJitLink, NVTX, triton are not needed): ~4 GB, about 80 s with a
# warm pip cache. Everything is pinned. pip then reports that torch's declared dependencies
# (cuda-toolkit, cuda-bindings, triton, a newer setuptools) are missing: expected, and the
# import-and-train check at the end is what decides success.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=.venv
stamp="$venv/.luxest-setup-4"
if [ -f "$stamp" ]; then
    exit 0
fi
python3 -m venv "$venv" 2>/dev/null || {
    echo "setup-python: python3 -m venv failed (Debian: apt-get install python3-venv)" >&2
    exit 1
}
pip=("$venv/bin/pip" install --quiet --disable-pip-version-check)
"${pip[@]}" --no-deps torch==2.15.0 \
    "nvidia-cublas==13.4.1.3.*" "nvidia-cuda-runtime==13.2.86.*" "nvidia-cuda-nvrtc==13.2.86.*" \
    "nvidia-cuda-cupti==13.2.86.*" "nvidia-cufft==12.2.0.57.*" "nvidia-cufile==1.17.1.22.*" \
    "nvidia-cusparse==12.7.10.12.*" nvidia-cudnn-cu13==9.26.0.51 nvidia-cusparselt-cu13==0.8.1 \
    nvidia-nccl-cu13==2.30.7 nvidia-nvshmem-cu13==3.7.2
"${pip[@]}" -r training/requirements.txt
# The contract module (python/luxest_contract.py: naming, header keys, EXR I/O, exposure) is
# importable from every script run with the venv's python, through a .pth file.
site=$("$venv/bin/python" -c "import sysconfig; print(sysconfig.get_paths()['purelib'])")
echo "$PWD/python" > "$site/luxest.pth"
"$venv/bin/python" -c "import torch, onnxruntime, OpenEXR, luxest_contract; torch.nn.Conv2d(3, 3, 3)(torch.rand(1, 3, 8, 8)).sum().backward()"
touch "$stamp"
echo "setup-python: ok ($venv)" >&2
