#!/usr/bin/env python3
"""Denoises images of a dataset split with an exported ONNX model (onnxruntime), writing
<out_dir>/<name>_<spp>spp.dn.exr with the noisy image's header plus luxest.denoiser (names and
keys from luxest_contract; spp from the headers)."""

import argparse
from pathlib import Path

import numpy as np
import onnxruntime as ort

import luxest_contract as contract
import progress
import transfer


def channels(session):
    """The features a model takes, in channel order (its `luxest.channels` metadata)."""
    meta = session.get_modelmeta().custom_metadata_map
    return [c.strip() for c in meta.get(contract.CHANNELS, ",".join(contract.FEATURES[:3])).split(",")]


def denoise(session, hdr, *features):
    """`features`: the images of channels(session)[1:], in that order. The radiance is scaled by
    2**e first (luxest_contract.range_exponent for the model's MEAN_LUMINANCE: dim images
    brightened, and bright ones dimmed where the model records it; as crates/denoise does) and
    the result by 2**-e."""
    names = channels(session)
    images = [hdr, *features]
    low = contract.model_mean_luminance(session.get_modelmeta().custom_metadata_map)
    e = contract.range_exponent(hdr, images[names.index("emi")] if "emi" in names else None, low)
    s = 2.0**e
    if e:
        images = [
            (np.asarray(im, dtype=np.float64) * s).astype(np.float32) if n in contract.RADIANCE_FEATURES else im
            for n, im in zip(names, images)
        ]
    x = np.concatenate(images, axis=-1).transpose(2, 0, 1)[None].astype(np.float32)
    feed = {contract.INPUT_TENSOR: x, contract.EXPOSURE_TENSOR: transfer.exposure_np(hdr, s)}
    out = session.run([contract.OUTPUT_TENSOR], feed)[0][0].transpose(1, 2, 0)
    return (out.astype(np.float64) / s).astype(np.float32) if e else out


def denoise_split(model, split_dir, out_dir, spp_levels=None, scan=None):
    """Denoises every noisy level (or those in spp_levels) of a split (`scan`: its
    contract.scan, when the caller has listed it already); returns
    [(name, spp, noisy hdr path, denoised path)]."""
    session = ort.InferenceSession(str(model), providers=["CPUExecutionProvider"])
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    wanted = channels(session)
    done = []
    scan = contract.scan(split_dir) if scan is None else scan
    total = sum(1 for levels in scan.values() for k in levels if k is not None and (not spp_levels or k in spp_levels))
    with progress.Progress("infer", total, "images") as shown:
        for name, levels in scan.items():
            for feats in (v for k, v in sorted(levels.items(), key=lambda kv: kv[0] or 0) if k is not None):
                noisy = contract.read(feats["hdr"])
                spp = noisy.value(contract.SAMPLES, required=True)
                if spp_levels and spp not in spp_levels:
                    continue
                dn = denoise(session, noisy.pixels, *(contract.read_rgb(feats[k]) for k in wanted[1:]))
                header = dict(noisy.header)
                header[contract.DENOISER] = Path(model).name
                path = out / contract.image_name(name, "dn", spp)
                contract.write(path, dn, header)
                done.append((name, spp, feats["hdr"], path))
                shown.update()
    return done


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--split-dir", required=True)
    ap.add_argument("--out-dir", required=True)
    ap.add_argument("--spp", type=int, nargs="+")
    args = ap.parse_args(argv)
    denoise_split(args.model, args.split_dir, args.out_dir, args.spp)
    print(f"infer: wrote denoised images to {args.out_dir}")


if __name__ == "__main__":
    main()
