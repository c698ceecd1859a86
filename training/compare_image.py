#!/usr/bin/env python3
"""PSNR and SSIM of noisy and denoised images against the references of a split.

Both metrics are computed on tonemapped images: x / (1 + x) after scaling by the reference's
autoexposure (transfer.py's exposure), clipped to [0, 1], per channel; SSIM with an 11-tap
Gaussian window (sigma 1.5), K1 = 0.01, K2 = 0.03, averaged over channels. Prints per level the
mean over scenes and the gain of denoising; --json writes the numbers."""
import argparse
import json
import math
from pathlib import Path

import numpy as np
import onnxruntime as ort
import torch

import dataset
import exrio
import infer
import loss
import transfer


def tonemap(img, exposure):
    x = np.clip(img, 0, None) * exposure
    return np.clip(x / (1.0 + x), 0.0, 1.0)


def psnr(a, b):
    mse = float(np.mean((a - b) ** 2))
    return 10 * math.log10(1.0 / max(mse, 1e-12))


def ssim(a, b):
    ta = torch.from_numpy(a.transpose(2, 0, 1).copy())[None].double()
    tb = torch.from_numpy(b.transpose(2, 0, 1).copy())[None].double()
    return float(_ssim_map(ta, tb, loss._window(3).double()))


def _ssim_map(a, b, win, c1=0.01 ** 2, c2=0.03 ** 2):
    import torch.nn.functional as F

    pad = win.shape[-1] // 2
    f = lambda t: F.conv2d(F.pad(t, (pad,) * 4, mode="reflect"), win, groups=3)
    mu_a, mu_b = f(a), f(b)
    s_aa, s_bb, s_ab = f(a * a) - mu_a ** 2, f(b * b) - mu_b ** 2, f(a * b) - mu_a * mu_b
    m = ((2 * mu_a * mu_b + c1) * (2 * s_ab + c2)) / ((mu_a ** 2 + mu_b ** 2 + c1) * (s_aa + s_bb + c2))
    return m.mean()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--split-dir", required=True)
    ap.add_argument("--spp", type=int, nargs="+", default=[1, 4, 16, 64])
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    session = ort.InferenceSession(args.model, providers=["CPUExecutionProvider"])
    rows = {}
    for name, levels in dataset.scan(args.split_dir).items():
        ref = exrio.read(levels[None]["hdr"])
        exp = float(transfer.exposure(torch.from_numpy(ref.transpose(2, 0, 1).copy())[None]))
        r = tonemap(ref, exp)
        for spp in args.spp:
            if spp not in levels:
                continue
            f = levels[spp]
            noisy = exrio.read(f["hdr"])
            dn = infer.denoise(session, noisy, exrio.read(f["alb"]), exrio.read(f["nrm"]))
            n, d = tonemap(noisy, exp), tonemap(dn, exp)
            rows.setdefault(spp, []).append((psnr(n, r), psnr(d, r), ssim(n, r), ssim(d, r)))
    print(f"{'spp':>5} {'scenes':>6} {'PSNR noisy':>11} {'PSNR denoised':>14} {'gain dB':>8} {'SSIM noisy':>11} {'SSIM denoised':>14}")
    summary = {}
    for spp, vals in sorted(rows.items()):
        m = [sum(v[k] for v in vals) / len(vals) for k in range(4)]
        summary[spp] = {"psnr_noisy": m[0], "psnr_denoised": m[1], "ssim_noisy": m[2], "ssim_denoised": m[3], "scenes": len(vals)}
        print(f"{spp:>5} {len(vals):>6} {m[0]:>11.2f} {m[1]:>14.2f} {m[1] - m[0]:>8.2f} {m[2]:>11.4f} {m[3]:>14.4f}")
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main()
