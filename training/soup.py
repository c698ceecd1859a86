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
from pathlib import Path

import torch

import config
import export


def load(path):
    """(Config, state dict, file read) of an ingredient: an exported model, a run directory or a
    run's checkpoint.pt."""
    path = Path(path)
    if path.is_dir():
        path = path / "checkpoint.pt"
    if not path.is_file():
        raise SystemExit(f"soup: {path}: no such file")
    if path.suffix == ".onnx":
        try:
            cfg, state = export.load_onnx(path)
        except Exception as e:  # onnx's own errors name neither the file nor the problem briefly
            raise SystemExit(f"soup: {path}: not a model exported by export.py ({str(e).splitlines()[0]})")
        return cfg, state, path
    if not (path.parent / "config.json").is_file():
        raise SystemExit(f"soup: {path}: no config.json beside it (not a training run)")
    cfg = config.Config.load(path.parent / "config.json")
    try:
        state = torch.load(path, weights_only=False, map_location="cpu")["model"]
    except Exception as e:
        raise SystemExit(f"soup: {path}: not a training checkpoint ({str(e).splitlines()[0]})")
    return cfg, state, path


def network(cfg):
    return {k: getattr(cfg, k) for k in config.NETWORK}


def soup(ingredients, weights=None):
    """(Config of the first ingredient, the weighted mean of the ingredients' weights, the files
    read). Weights default to equal; they are normalised to sum to one. The mean is taken in
    float64 and stored in each tensor's own type."""
    if not ingredients:
        raise SystemExit("soup: no ingredients")
    weights = [1.0] * len(ingredients) if weights is None else [float(w) for w in weights]
    if len(weights) != len(ingredients):
        raise SystemExit(f"soup: {len(weights)} weights for {len(ingredients)} ingredients")
    if any(w < 0 for w in weights) or sum(weights) <= 0:
        raise SystemExit("soup: weights must be non-negative and not all zero")
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
            if any(not torch.equal(s[k], t) for _, s, _ in loaded[1:]):
                raise SystemExit(f"soup: {k}: integer weights that differ between ingredients")
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
    run = Path(run_dir)
    run.mkdir(parents=True, exist_ok=True)
    cfg.run_dir = str(run_dir)
    cfg.save(run / "config.json")
    torch.save({"model": state, "step": None}, run / "checkpoint.pt")
    record = {"ingredients": [{"path": str(p), "sha256": sha256(p), "weight": w} for p, w in zip(files, weights)]}
    (run / "soup.json").write_text(json.dumps(record, indent=2) + "\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("ingredients", nargs="+", help="exported models (.onnx), run directories or checkpoint.pt files")
    ap.add_argument("--weights", type=float, nargs="+", help="one per ingredient (default: equal)")
    ap.add_argument("--run-dir", required=True, help="where the soup's config.json, checkpoint.pt and soup.json go")
    ap.add_argument("--out", help="also export the soup to this ONNX file (export.py)")
    args = ap.parse_args(argv)
    run = Path(args.run_dir).resolve()
    inputs = {Path(p).resolve() for p in args.ingredients}
    if run in inputs or any(run == p.parent for p in inputs if p.suffix == ".pt"):
        raise SystemExit(f"soup: --run-dir {args.run_dir}: is an ingredient's run (it would be overwritten)")
    if args.out and Path(args.out).resolve() in inputs:
        raise SystemExit(f"soup: --out {args.out}: is an ingredient (it would be overwritten)")
    cfg, state, files, weights = soup(args.ingredients, args.weights)
    write(run, cfg, state, files, weights)
    print(f"soup: {len(files)} ingredients -> {run}")
    if args.out:
        export.export(run, args.out)


if __name__ == "__main__":
    main()
