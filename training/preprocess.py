#!/usr/bin/env python3
"""Converts a rendered dataset (data/<dataset>/<split>/*.exr) into float32 arrays for training:
inputs (H, W, 9) = hdr + alb + nrm per noisy level, references (H, W, 3). Incremental."""
from pathlib import Path

import numpy as np

import config
import dataset
import exrio


def main(argv=None):
    cfg = config.parse(argv, __doc__.splitlines()[0])
    n = 0
    for split in ["train", "valid", "test"]:
        src, dst = Path(cfg.data_dir) / split, Path(cfg.prep_dir) / split
        dst.mkdir(parents=True, exist_ok=True)
        for name, levels in dataset.scan(src).items():
            if None not in levels or "hdr" not in levels[None]:
                raise SystemExit(f"{src}: {name} has no reference image")
            for spp, feats in levels.items():
                tag = "ref" if spp is None else f"{spp:06d}spp"
                out = dst / f"{name}_{tag}.npy"
                if spp is not None and spp not in cfg.noisy_spp:
                    continue
                newest = max(p.stat().st_mtime for p in feats.values())
                if out.exists() and out.stat().st_mtime >= newest:
                    continue
                if spp is None:
                    arr = exrio.read(feats["hdr"])
                else:
                    missing = [f for f in ("hdr", "alb", "nrm") if f not in feats]
                    if missing:
                        raise SystemExit(f"{src}: {name} at {spp} spp lacks {', '.join(missing)}")
                    arr = np.concatenate([exrio.read(feats[f]) for f in ("hdr", "alb", "nrm")], axis=-1)
                if not np.isfinite(arr).all():
                    raise SystemExit(f"{feats.get('hdr')}: non-finite values")
                tmp = out.with_suffix(".tmp.npy")
                np.save(tmp, arr)
                tmp.replace(out)
                n += 1
    print(f"preprocess: {n} arrays written to {cfg.prep_dir}")


if __name__ == "__main__":
    main()
