"""The HDR contract shared by training, export and every runtime (ARCHITECTURE.md, Models):

  exposure  = 0.18 / exp(mean over pixels of log(Y + 1e-4)),  Y the Rec. 709 luminance of hdr
  forward   = log1p(hdr * exposure)        (the network sees this, plus albedo and normals as is)
  inverse   = expm1(out) / exposure

The forward and inverse transfer are inside the exported ONNX graph, with the padding of H and W
to multiples of 16, so Rust feeds raw linear hdr/alb/nrm and gets linear radiance back. The
exposure is a second graph input, computed by the caller over the whole image (exposure_np here,
exposure() in crates/denoise): a large image denoised in tiles then uses one exposure, not one
per tile."""
import numpy as np
import torch

KEY = 0.18
EPS = 1e-4
LUMA = (0.2126, 0.7152, 0.0722)


def exposure(hdr):
    """Per-image autoexposure of an (N, 3, H, W) tensor, shape (N, 1, 1, 1)."""
    y = hdr[:, 0:1] * LUMA[0] + hdr[:, 1:2] * LUMA[1] + hdr[:, 2:3] * LUMA[2]
    mean_log = torch.log(y.clamp(min=0) + EPS).mean(dim=(1, 2, 3), keepdim=True)
    return KEY / torch.exp(mean_log)


def forward(hdr, exp):
    return torch.log1p(hdr.clamp(min=0) * exp)


def inverse(x, exp):
    return torch.expm1(x) / exp


def exposure_np(hdr):
    """exposure() of one (H, W, 3) image as a float32 array of shape (1,), accumulated in f64."""
    y = hdr[..., 0].astype(np.float64) * LUMA[0] + hdr[..., 1] * LUMA[1] + hdr[..., 2] * LUMA[2]
    mean_log = np.log(np.maximum(y, 0.0) + EPS).mean()
    return np.array([KEY / np.exp(mean_log)], dtype=np.float32)
