#!/usr/bin/env python3
"""Denoises images of a dataset split with an exported ONNX model (onnxruntime), writing
<out_dir>/<name>_<spp>spp.dn.exr."""
import argparse
from pathlib import Path

import numpy as np
import onnxruntime as ort

import dataset
import exrio
import transfer


def denoise(session, hdr, alb, nrm):
    x = np.concatenate([hdr, alb, nrm], axis=-1).transpose(2, 0, 1)[None].astype(np.float32)
    feed = {"input": x, "exposure": transfer.exposure_np(hdr)}
    return session.run(None, feed)[0][0].transpose(1, 2, 0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--split-dir", required=True)
    ap.add_argument("--out-dir", required=True)
    ap.add_argument("--spp", type=int, nargs="+", default=[1, 4, 16, 64])
    args = ap.parse_args(argv)
    session = ort.InferenceSession(args.model, providers=["CPUExecutionProvider"])
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for name, levels in dataset.scan(args.split_dir).items():
        for spp in args.spp:
            if spp in levels:
                f = levels[spp]
                dn = denoise(session, *(exrio.read(f[k]) for k in ("hdr", "alb", "nrm")))
                exrio.write(out / f"{name}_{spp:06d}spp.dn.exr", dn)
    print(f"infer: wrote denoised images to {out}")


if __name__ == "__main__":
    main()
