#!/usr/bin/env python3
"""Exports a trained run to ONNX: inputs `input` (N, 3 x features, H, W) = raw linear hdr + alb +
nrm (+ emi [+ ema]: the run's `features`, listed in the metadata `luxest.channels`) and
`exposure` (N,) = transfer.exposure of each whole image, output `output` (N, 3, H, W) linear
radiance (the names: luxest_contract.TENSORS), dynamic H and W; the log1p transfer and the padding to multiples of 16 are inside the
graph (transfer.py), the exposure formula is recorded in the metadata."""

import argparse
import json
import tempfile
from dataclasses import asdict
from pathlib import Path

import numpy as np
import onnx
import torch

import config
import luxest_contract as contract
import model


def outputs(head, scales=model.SCALES):
    """What the graph's output is for `head` (model.py), in the metadata's transfer description."""
    if head == "direct":
        return "output: the network's transferred radiance, inverted in graph (expm1(out) / exposure)"
    return (
        f"output: predicted {model.KERNEL}x{model.KERNEL} kernels applied in graph to the linear "
        f"irradiance max(hdr, 0) / max(alb, {model.ALBEDO_FLOOR}) at {scales} scales (1 to "
        f"1/{2 ** (scales - 1)}), combined by predicted blend weights, times max(alb, "
        f"{model.ALBEDO_FLOOR})"
    )


DETAIL_GATE = (
    "; with the detail gate: each finer scale keeps a predicted fraction sigmoid(logit) "
    "of its filtered detail f - U(D(f)) (U(D(f)): f's 2x2 means, bilinearly upsampled) "
    "before the blend"
)
"""The metadata's addition for `kpn` models with detail gates (model.py)."""
EMISSION = (
    "; with the emi feature: the network filters max(hdr - emi, 0) in place of hdr (and "
    "sees log1p(emi * exposure) as 3 more channels), and max(emi, 0) is added to its output"
)
"""The metadata's addition for models that take the emission (model.py)."""
EMISSION_AA = "; with the ema feature (the emission antialiased): max(ema, 0) is added in place of max(emi, 0)"
"""The metadata's addition for models that add back the antialiased emission."""


def load_onnx(model_path):
    """(Config, state dict) of an exported model, read from its metadata (`luxest.config`) and
    initializers."""
    from onnx import numpy_helper

    m = onnx.load(str(model_path))
    meta = {p.key: p.value for p in m.metadata_props}
    if contract.MODEL_CONFIG not in meta:
        raise ValueError(f"{model_path}: no {contract.MODEL_CONFIG} metadata (not exported by export.py)")
    cfg = config.Config.from_values(json.loads(meta[contract.MODEL_CONFIG]))
    net = model.denoiser(cfg)
    weights = {i.name: numpy_helper.to_array(i) for i in m.graph.initializer}
    state = net.state_dict()
    for k in state:  # a decoder join's weight exported in two halves (model.UNet.split_joins)
        block = k.removeprefix("unet.").removesuffix(".0.0.weight")
        up, skip = (f"unet.joins.{block}_{part}" for part in ("up", "skip"))
        if k not in weights and up in weights and skip in weights:
            weights[k] = np.concatenate([weights[up], weights[skip]], axis=1)
    for k in state:  # a bias of zeros the exporter's optimiser dropped from its Conv (a grown model's new head)
        if k.endswith(".bias") and k not in weights and k.removesuffix(".bias") + ".weight" in weights:
            weights[k] = np.zeros(tuple(state[k].shape), dtype=np.float32)
    missing = [k for k in state if k not in weights or tuple(weights[k].shape) != tuple(state[k].shape)]
    if missing:
        raise ValueError(f"{model_path}: lacks the weights {', '.join(missing[:3])}")
    return cfg, {k: torch.from_numpy(weights[k].copy()) for k in state}


def temp_of(path):
    """Where a file is written before it is renamed to `path` (write_run, export)."""
    return Path(str(path) + ".tmp")


def write_run(run_dir, cfg, state, extra=None):
    """A run directory of weights without a training behind them (config.json of `cfg`,
    checkpoint.pt of `state` with no step or optimiser state) and the `extra` text files {name:
    text}: each written beside its name first, then all renamed, so an earlier such run there is
    replaced whole."""
    run = Path(run_dir)
    run.mkdir(parents=True, exist_ok=True)
    tmp = {name: temp_of(run / name) for name in ("config.json", "checkpoint.pt", *(extra or {}))}
    cfg.save(tmp["config.json"])
    torch.save({"model": state, "step": None}, tmp["checkpoint.pt"])
    for name, text in (extra or {}).items():
        tmp[name].write_text(text)
    for name, t in tmp.items():
        t.replace(run / name)


def run_from_onnx(model_path, run_dir):
    """Writes a run directory (config.json, checkpoint.pt) holding the configuration and weights
    of an exported model (load_onnx), so that a committed model can be exported again (e.g. with
    --antialiased-emission) without its run."""
    cfg, state = load_onnx(model_path)
    write_run(run_dir, cfg, state)


def export(run_dir, out_path, metrics=None, antialiased_emission=False):
    """`antialiased_emission`: export a run trained with the emi feature alone as a model that
    adds back ema instead (the network does not see ema, so the weights are the same; model.py)."""
    cfg = config.Config.load(Path(run_dir) / "config.json")
    if antialiased_emission:
        if "emi" not in cfg.features:
            raise ValueError(f"{run_dir}: --antialiased-emission needs a run with the emi feature")
        cfg.features = [f for f in cfg.features if f != "ema"] + ["ema"]
    net = model.denoiser(cfg)
    net.load_state_dict(torch.load(Path(run_dir) / "checkpoint.pt", weights_only=False, map_location="cpu")["model"])
    net.eval()
    net.kernel_gather = "slices"
    net.unet.split_joins()  # no Concat node in the decoder (model.UNet.split_joins)
    x = torch.rand(1, net.in_channels, 48, 64)
    e = torch.tensor([0.5])
    h, w = torch.export.Dim("h", min=1, max=16384), torch.export.Dim("w", min=1, max=16384)
    tmp = temp_of(out_path)
    torch.onnx.export(
        net,
        (x, e),
        str(tmp),
        input_names=[contract.INPUT_TENSOR, contract.EXPOSURE_TENSOR],
        output_names=[contract.OUTPUT_TENSOR],
        dynamic_shapes={"x": {2: h, 3: w}, "exposure": None},
        external_data=False,
    )
    proto = onnx.load(str(tmp))
    meta = {
        contract.CHANNELS: ",".join(net.features),
        contract.MODEL_TRANSFER: "log1p(max(hdr, 0) * exposure) in graph; input exposure (N,) = 0.18 / "
        "exp(mean over the whole image of log(max(Y, 0) + 1e-4)), Y = Rec. 709 luminance of hdr; "
        + outputs(cfg.head, net.scales)
        + (DETAIL_GATE if net.detail_gate else "")
        + (EMISSION if net.emission else "")
        + (EMISSION_AA if "ema" in net.features else ""),
        contract.MODEL_PADDING: "replicate to multiples of 16; in graph",
        contract.MODEL_CONFIG: json.dumps(asdict(cfg)),
    }
    meta[contract.FEATURE_SAMPLES] = str(config.feature_samples(cfg))
    if config.scale_luminance(cfg) is not None:
        meta[contract.MEAN_LUMINANCE] = repr(float(cfg.mean_luminance))
    if metrics:
        meta[contract.MODEL_METRICS] = json.dumps(metrics)
    for k, v in meta.items():
        p = proto.metadata_props.add()
        p.key, p.value = k, v
    onnx.save(proto, str(tmp))
    tmp.replace(out_path)
    print(f"export: wrote {out_path}")


SETTABLE = (contract.FEATURE_SAMPLES, contract.MEAN_LUMINANCE)
"""The metadata keys `--set-metadata` sets: what a model takes, recorded after its export."""


def set_metadata(model_path, values):
    """Sets the metadata entries `values` ({key: text}) of an exported model in place (weights
    and graph unchanged): how a model exported before a key existed gets it, e.g. the
    FEATURE_SAMPLES of the antialiased features it was trained on."""
    proto = onnx.load(str(model_path))
    props = {p.key: p for p in proto.metadata_props}
    for k, v in values.items():
        if k in props:
            props[k].value = v
        else:
            p = proto.metadata_props.add()
            p.key, p.value = k, v
    tmp = temp_of(model_path)
    onnx.save(proto, str(tmp))
    tmp.replace(model_path)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--run-dir", help="the training run (config.json, checkpoint.pt)")
    src.add_argument("--from-onnx", help="a model exported by this script: its configuration and weights")
    src.add_argument(
        "--set-metadata",
        nargs="+",
        metavar="KEY=VALUE",
        help="set metadata entries KEY=VALUE of the model --out in place (SETTABLE: its feature samples, mean luminance)",
    )
    ap.add_argument("--out", required=True)
    ap.add_argument(
        "--antialiased-emission",
        action="store_true",
        help="export a run trained with the emi feature as a model that adds back ema (same weights)",
    )
    args = ap.parse_args(argv)
    if args.set_metadata:
        pairs = [kv.partition("=") for kv in args.set_metadata]
        bad = [k for k, eq, _ in pairs if not eq or k not in SETTABLE]
        if bad or not Path(args.out).is_file():
            raise SystemExit(
                f"export: --set-metadata: expected KEY=VALUE pairs of {', '.join(SETTABLE)} and an existing "
                f"--out model ({', '.join(bad) or args.out})"
            )
        set_metadata(args.out, {k: v for k, _, v in pairs})
        print(f"export: set {', '.join(k for k, _, _ in pairs)} in {args.out}")
        return
    needed = (
        [Path(args.from_onnx)] if args.from_onnx else [Path(args.run_dir) / f for f in ("config.json", "checkpoint.pt")]
    )
    for f in needed:
        if not f.is_file():
            raise SystemExit(f"export: {f}: not found" + ("" if args.from_onnx else " (train.py writes it)"))
    try:
        if args.from_onnx:
            with tempfile.TemporaryDirectory() as tmp:
                run_from_onnx(args.from_onnx, tmp)
                export(tmp, args.out, antialiased_emission=args.antialiased_emission)
        else:
            export(args.run_dir, args.out, antialiased_emission=args.antialiased_emission)
    except ValueError as e:
        raise SystemExit(f"export: {e}")


if __name__ == "__main__":
    main()
