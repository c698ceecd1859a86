#!/usr/bin/env python3
"""Averages the weights of several trainings of one network (a "model soup", Wortsman et al.
2022): fine-tunings that start from the same model stay in one basin of the loss, and the mean of
their weights often denoises better than each of them, at the inference cost of one
(docs/measurements.md, *Model soups*). Ingredients are exported models (.onnx) or training runs
(a run directory or its checkpoint.pt, with config.json beside it); all must be the same network
(width, head, features, detail gates). Writes a run directory (config.json: the first
ingredient's, with run_dir this one; checkpoint.pt; soup.json: the ingredients, their SHA-256 and
weights) that export.py exports; --out exports it at once."""

import argparse
import hashlib
import json
import math
from pathlib import Path

import torch

import config
import export


def first_line(e):
    """The first line of an exception's message, or its type's name when it has none."""
    return (str(e).splitlines() or [type(e).__name__])[0]


def checkpoint_of(path):
    """The file an ingredient's weights are read from: a run directory's checkpoint.pt, or the
    file itself."""
    path = Path(path)
    return path / "checkpoint.pt" if path.is_dir() else path


def files_read(path):
    """Every file an ingredient is read from (its weights, and a run's config.json)."""
    weights = checkpoint_of(path)
    return {weights} if weights.suffix == ".onnx" else {weights, weights.parent / "config.json"}


def load(path):
    """(Config, state dict, file read) of an ingredient: an exported model, a run directory or a
    run's checkpoint.pt."""
    path = checkpoint_of(path)
    if not path.is_file():
        raise SystemExit(f"soup: {path}: no such file")
    if path.suffix == ".onnx":
        try:
            cfg, state = export.load_onnx(path)
        except Exception as e:  # onnx's own errors name neither the file nor the problem briefly
            raise SystemExit(f"soup: {path}: not a model exported by export.py ({first_line(e)})")
        return cfg, state, path
    if not (path.parent / "config.json").is_file():
        raise SystemExit(f"soup: {path}: no config.json beside it (not a training run)")
    try:
        cfg = config.Config.load(path.parent / "config.json")
    except Exception as e:
        raise SystemExit(f"soup: {path.parent / 'config.json'}: not a run configuration ({first_line(e)})")
    try:
        state = torch.load(path, weights_only=False, map_location="cpu")["model"]
    except Exception as e:
        raise SystemExit(f"soup: {path}: not a training checkpoint ({first_line(e)})")
    if not isinstance(state, dict) or not all(isinstance(t, torch.Tensor) for t in state.values()):
        raise SystemExit(f"soup: {path}: not a training checkpoint (its 'model' is not a state dict)")
    return cfg, state, path


def network(cfg):
    return {k: getattr(cfg, k) for k in config.NETWORK}


def soup(ingredients, weights=None):
    """(Config of the first ingredient, the weighted mean of the ingredients' weights, the files
    read, the normalised weights). Weights default to equal; they are normalised to sum to one.
    The mean is taken in float64 and stored in each tensor's own type."""
    if not ingredients:
        raise SystemExit("soup: no ingredients")
    weights = [1.0] * len(ingredients) if weights is None else [float(w) for w in weights]
    if len(weights) != len(ingredients):
        raise SystemExit(f"soup: {len(weights)} weights for {len(ingredients)} ingredients")
    if not all(math.isfinite(w) and w >= 0 for w in weights) or sum(weights) <= 0:
        raise SystemExit(
            f"soup: --weights {' '.join(map(str, weights))}: must be finite, non-negative and not all zero"
        )
    loaded = [load(p) for p in ingredients]
    cfg0, state0, path0 = loaded[0]
    for cfg, state, path in loaded[1:]:
        if network(cfg) != network(cfg0):
            theirs = ", ".join(f"{k} {v}" for k, v in network(cfg).items())
            ours = ", ".join(f"{k} {v}" for k, v in network(cfg0).items())
            raise SystemExit(f"soup: {path}: another network ({theirs}) than {path0} ({ours})")
        if state.keys() != state0.keys() or any(state[k].shape != state0[k].shape for k in state0):
            raise SystemExit(f"soup: {path}: weights of another shape than {path0}'s")
    total = sum(weights)
    mean = {}
    for k, t in state0.items():
        if not t.is_floating_point():
            for _, s, path in loaded[1:]:
                if not torch.equal(s[k], t):
                    raise SystemExit(f"soup: {path}: its integer tensor {k} differs from {path0}'s")
            mean[k] = t.clone()
            continue
        acc = sum((w / total) * s[k].double() for w, (_, s, _) in zip(weights, loaded))
        mean[k] = acc.to(t.dtype)
    return cfg0, mean, [p for _, _, p in loaded], [w / total for w in weights]


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def write(run_dir, cfg, state, files, weights):
    """The soup's run directory: the first ingredient's configuration (the network; its training
    fields are that ingredient's) with run_dir this directory, the weights, soup.json."""
    cfg.run_dir = str(run_dir)
    record = {"ingredients": [{"path": str(p), "sha256": sha256(p), "weight": w} for p, w in zip(files, weights)]}
    export.write_run(run_dir, cfg, state, {"soup.json": json.dumps(record, indent=2) + "\n"})


def plan(ingredients, run_dir, out):
    """Refuses, before anything is written, outputs that would overwrite an ingredient's files or
    each other, an --out that cannot be written, and a --run-dir that holds something other than
    an earlier soup."""
    run = Path(run_dir)
    outputs = {run / "config.json": "--run-dir", run / "checkpoint.pt": "--run-dir", run / "soup.json": "--run-dir"}
    if out:
        out = Path(out)
        if out.resolve() in {p.resolve() for p in outputs}:
            raise SystemExit(f"soup: --out {out}: is one of --run-dir's files")
        outputs.update({out: "--out", export.temp_of(out): "--out"})
        if out.is_dir() or not out.resolve().parent.is_dir():
            raise SystemExit(f"soup: --out {out}: not a file in an existing directory")
    read = {f.resolve() for p in ingredients for f in files_read(p)}
    for o, flag in outputs.items():
        if o.resolve() in read:
            raise SystemExit(f"soup: {flag} {o}: is an ingredient's file (it would be overwritten)")
        if o.exists() and not o.is_file():
            raise SystemExit(f"soup: {flag} {o}: exists and is not a regular file")
    if run.exists() and not run.is_dir():
        raise SystemExit(f"soup: --run-dir {run}: exists and is not a directory")
    if run.is_dir() and any(run.iterdir()) and not (run / "soup.json").is_file():
        raise SystemExit(f"soup: --run-dir {run}: holds something other than a soup (no soup.json); not overwritten")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("ingredients", nargs="+", help="exported models (.onnx), run directories or checkpoint.pt files")
    ap.add_argument("--weights", type=float, nargs="+", help="one per ingredient (default: equal)")
    ap.add_argument("--run-dir", required=True, help="where the soup's config.json, checkpoint.pt and soup.json go")
    ap.add_argument("--out", help="also export the soup to this ONNX file (export.py)")
    args = ap.parse_args(argv)
    plan(args.ingredients, args.run_dir, args.out)
    cfg, state, files, weights = soup(args.ingredients, args.weights)
    write(args.run_dir, cfg, state, files, weights)
    print(f"soup: {len(files)} ingredients -> {args.run_dir}")
    if args.out:
        export.export(args.run_dir, args.out)


if __name__ == "__main__":
    main()
