#!/usr/bin/env python3
"""Exports a trained run to ONNX: inputs `input` (N, 3 x features, H, W) = raw linear hdr + alb +
nrm (+ emi: the run's `features`, listed in the metadata `luxest.channels`) and
`exposure` (N,) = transfer.exposure of each whole image, output `output` (N, 3, H, W) linear
radiance, dynamic H and W; the log1p transfer and the padding to multiples of 16 are inside the
graph (transfer.py), the exposure formula is recorded in the metadata."""
import argparse
import json
from dataclasses import asdict
from pathlib import Path

import onnx
import torch

import config
import luxest_contract as contract
import model
from model import Denoiser


OUTPUTS = {
    "direct": "output: the network's transferred radiance, inverted in graph (expm1(out) / exposure)",
    "kpn": f"output: predicted {model.KERNEL}x{model.KERNEL} kernels applied in graph to the linear "
           f"irradiance max(hdr, 0) / max(alb, {model.ALBEDO_FLOOR}) at {model.SCALES} scales (1 to "
           f"1/{2 ** (model.SCALES - 1)}), combined by predicted blend weights, times max(alb, "
           f"{model.ALBEDO_FLOOR})",
}
"""What the graph's output is, per head (model.py), in the metadata's transfer description."""
EMISSION = ("; with the emi feature: the network filters max(hdr - emi, 0) in place of hdr (and "
            "sees log1p(emi * exposure) as 3 more channels), and max(emi, 0) is added to its output")
"""The metadata's addition for models that take the emission (model.py)."""


def export(run_dir, out_path, metrics=None):
    cfg = config.Config.load(Path(run_dir) / "config.json")
    net = Denoiser(width=cfg.base_width, head=cfg.head, features=cfg.features)
    net.load_state_dict(torch.load(Path(run_dir) / "checkpoint.pt", weights_only=False)["model"])
    net.eval()
    net.kernel_gather = "slices"
    x = torch.rand(1, net.in_channels, 48, 64)
    e = torch.tensor([0.5])
    h, w = torch.export.Dim("h", min=1, max=16384), torch.export.Dim("w", min=1, max=16384)
    tmp = Path(str(out_path) + ".tmp")
    torch.onnx.export(net, (x, e), str(tmp), input_names=["input", "exposure"],
                      output_names=["output"], dynamic_shapes={"x": {2: h, 3: w}, "exposure": None},
                      external_data=False)
    model = onnx.load(str(tmp))
    meta = {
        contract.CHANNELS: ",".join(net.features),
        contract.MODEL_TRANSFER: "log1p(max(hdr, 0) * exposure) in graph; input exposure (N,) = 0.18 / "
        "exp(mean over the whole image of log(max(Y, 0) + 1e-4)), Y = Rec. 709 luminance of hdr; "
        + OUTPUTS[cfg.head] + (EMISSION if net.emission else ""),
        contract.MODEL_PADDING: "replicate to multiples of 16; in graph",
        contract.MODEL_CONFIG: json.dumps(asdict(cfg)),
    }
    if metrics:
        meta[contract.MODEL_METRICS] = json.dumps(metrics)
    for k, v in meta.items():
        p = model.metadata_props.add()
        p.key, p.value = k, v
    onnx.save(model, str(tmp))
    tmp.replace(out_path)
    print(f"export: wrote {out_path}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--run-dir", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    export(args.run_dir, args.out)


if __name__ == "__main__":
    main()
