"""The HDR transfer shared by training, export and every runtime (docs/architecture.md, Models):

  forward   = log1p(max(hdr, 0) * exposure)  (the network sees this, plus albedo and normals as is)
  inverse   = expm1(out) / exposure

`exposure` is the autoexposure of the *whole* image, `luxest_contract.exposure` (the one Python
copy of the formula, tied to Rust's `RgbImage::autoexposure` by tests/fixtures/contract). The
forward and inverse transfer are inside the exported ONNX graph, with the padding of H and W to
multiples of 16, so Rust feeds raw linear hdr/alb/nrm plus the exposure and gets linear radiance
back; a large image denoised in tiles uses one exposure, not one per tile. Training uses the
exposure preprocess.py stored for each whole image, never one computed from a crop."""

import numpy as np
import torch

import luxest_contract as contract


def exposure_of(hdr):
    """The whole-image exposure of each image of an (N, 3, H, W) tensor, as (N,) float32 —
    for callers holding whole images as tensors (tests, parity checks)."""
    a = hdr.detach().to("cpu", torch.float64).permute(0, 2, 3, 1).numpy()
    return torch.tensor([contract.exposure(img) for img in a], dtype=torch.float32, device=hdr.device)


def forward(hdr, exp):
    return torch.log1p(hdr.clamp(min=0) * exp)


def inverse(x, exp):
    return torch.expm1(x) / exp


def exposure_np(hdr, scale=1.0):
    """The exposure of one whole (H, W, 3) image (times `scale`: contract.exposure) as the model's
    `exposure` input, (1,) float32."""
    return np.array([contract.exposure(hdr, scale)], dtype=np.float32)
