"""The training losses (train.py --loss).

l1: L1 + MS-SSIM on transferred images (Zhao et al., "Loss Functions for Image Restoration with
Neural Networks", 2017). MS-SSIM with a Gaussian window (sigma 1.5, 11 taps), 3 scales with
weights renormalised from Wang et al. 2003, on images in [0, ~1] (log1p of exposed radiance).

psnr: minus the PSNR that `evaluate images` scores, per crop, averaged over the batch: the mean
squared error of the evaluation's tonemap (`display`, with the reference's whole-image exposure)
in decibels. L1 is minimised by a median of what the input leaves uncertain (an edge under 1 spp,
a firefly), the squared error by its mean; the log of each crop's error weighs each crop's
relative improvement alike, as the per-image PSNR averaged over images and noise levels does."""

import math

import torch
import torch.nn.functional as F

WEIGHTS = torch.tensor([0.0448, 0.2856, 0.3001])
WEIGHTS = WEIGHTS / WEIGHTS.sum()


def _window(channels, size=11, sigma=1.5):
    g = torch.exp(-((torch.arange(size) - size // 2) ** 2) / (2 * sigma**2))
    g = (g / g.sum()).float()
    w = g[:, None] * g[None, :]
    return w.expand(channels, 1, size, size).contiguous()


def _ssim_parts(a, b, win, c1=0.01**2, c2=0.03**2):
    ch = a.shape[1]
    pad = win.shape[-1] // 2
    mu_a = F.conv2d(F.pad(a, (pad,) * 4, mode="reflect"), win, groups=ch)
    mu_b = F.conv2d(F.pad(b, (pad,) * 4, mode="reflect"), win, groups=ch)
    f = lambda t: F.conv2d(F.pad(t, (pad,) * 4, mode="reflect"), win, groups=ch)
    s_aa = f(a * a) - mu_a**2
    s_bb = f(b * b) - mu_b**2
    s_ab = f(a * b) - mu_a * mu_b
    cs = (2 * s_ab + c2) / (s_aa + s_bb + c2)
    lum = (2 * mu_a * mu_b + c1) / (mu_a**2 + mu_b**2 + c1)
    return lum.mean(dim=(1, 2, 3)), cs.clamp(min=1e-6).mean(dim=(1, 2, 3))


def ms_ssim(a, b):
    win = _window(a.shape[1]).to(device=a.device, dtype=a.dtype)
    value = 1.0
    for i, w in enumerate(WEIGHTS):
        lum, cs = _ssim_parts(a, b, win)
        if i == len(WEIGHTS) - 1:
            value = value * (lum.clamp(min=1e-6) * cs) ** float(w)
        else:
            value = value * cs ** float(w)
            a, b = F.avg_pool2d(a, 2), F.avg_pool2d(b, 2)
    return value.mean()


def loss(pred, target, ms_ssim_weight):
    l1 = (pred - target).abs().mean()
    return (1 - ms_ssim_weight) * l1 + ms_ssim_weight * (1 - ms_ssim(pred, target))


SRGB_KNEE = 0.0031308
PSNR_FLOOR = 1e-6
"""Added to each crop's mean squared error before its log (60 dB): a flat crop matched exactly
does not weigh without bound."""


def display(x, k):
    """`evaluate images`' tonemap (`evaluate::metrics::tonemap`, crates/evaluate/src/metrics/mod.rs;
    tied by tests/fixtures/contract/exposure.json) of linear (N, 3, H, W) radiance with exposures
    k (N,): max(x, 0) k, Reinhard x / (1 + x), sRGB OETF, clamped to [0, 1]."""
    # inf (a direct head's expm1 overflow) maps to 1, not NaN.
    v = (x.clamp(min=0) * k.view(-1, 1, 1, 1)).clamp(max=1e30)
    t = v / (1 + v)
    return torch.where(t <= SRGB_KNEE, 12.92 * t, 1.055 * t.clamp(min=SRGB_KNEE) ** (1 / 2.4) - 0.055).clamp(0, 1)


def psnr_loss(pred, ref, k):
    """Minus the mean over the batch of each crop's PSNR (dB) of `display(pred, k)` against
    `display(ref, k)`: linear radiance, k the reference's whole-image exposure."""
    mse = ((display(pred, k) - display(ref, k)) ** 2).mean(dim=(1, 2, 3))
    return (10.0 / math.log(10.0)) * torch.log(mse + PSNR_FLOOR).mean()
