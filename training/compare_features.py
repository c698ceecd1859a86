#!/usr/bin/env python3
"""Scores denoising models on one scene with both kinds of features, in one run: antialiased
(aov-write --min-samples FEATURE_SPP, what make run and make eval write) and the default ones at
each snapshot's own sample count (aov-write --min-samples 1), by `evaluate images` (the
scoring of make eval: PSNR, SSIM and FLIP on the evaluation tonemap) against an independent
reference — the comparison that decides whether a fine-tuned model replaces the committed one
(models/README.md).

  compare_features.py --scene build/cornell-box/scene.lxs --models OLD.onnx NEW.onnx \\
      --work-dir build/compare-features [--spp 1 4 16 64] [--ref-spp 4096] [--resolution 256x256]

Renders (once; existing files are kept) the reference (seed REF_SEED), one progressive run of
the snapshots (seed NOISY_SEED) and both feature sets; denoises every snapshot with every model
and feature set (into model-<model's file stem>/, again when the model is newer) (`denoise` refuses features a model's metadata does not take: reported as
refused); writes <work-dir>/scores.csv (evaluate's) and prints a table per feature set."""

import argparse
import csv
import subprocess
import sys
from pathlib import Path

import config
import luxest_contract as contract

REF_SEED, NOISY_SEED = 1000001, 1
"""pipelines/presets.mk's seeds (docs/architecture.md, *Seeds*)."""
FEATURE_SETS = ("antialiased", "own")
METRICS = ("psnr_db", "ssim", "flip")


def run(cmd):
    """Runs a stage; its error output on failure (None on success)."""
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, check=False)
    return None if p.returncode == 0 else (p.stderr.strip().splitlines() or ["failed"])[-1]


def render(args, bins, work):
    """The reference, the snapshots and both feature sets under `work` (skipped when present)."""
    top, snaps = max(args.spp), ",".join(str(s) for s in args.spp)
    common = ["--resolution", args.resolution]
    ref = Path(contract.image_name(str(work / "scene"), "hdr"))
    if not ref.exists():
        err = run(
            [
                bins / "trace",
                args.scene,
                "--spp",
                args.ref_spp,
                "--reference",
                "--seed",
                REF_SEED,
                *common,
                "-o",
                work / "scene",
            ]
        )
        if err:
            sys.exit(f"compare_features: trace (reference): {err}")
    if not Path(contract.image_name(str(work / "scene"), "hdr", top)).exists():
        err = run(
            [
                bins / "trace",
                args.scene,
                "--spp",
                top,
                "--snapshots",
                snaps,
                "--seed",
                NOISY_SEED,
                *common,
                "-o",
                work / "scene",
            ]
        )
        if err:
            sys.exit(f"compare_features: trace: {err}")
    for kind, extra in zip(FEATURE_SETS, (["--min-samples", args.feature_spp], ["--min-samples", 1])):
        (work / kind).mkdir(exist_ok=True)
        if not Path(contract.image_name(str(work / kind / "scene"), "nrm", top)).exists():
            err = run(
                [
                    bins / "aov-write",
                    args.scene,
                    "--spp",
                    top,
                    "--snapshots",
                    snaps,
                    "--seed",
                    NOISY_SEED,
                    *extra,
                    *common,
                ]
                + ["-o", work / kind / "scene"]
            )
            if err:
                sys.exit(f"compare_features: aov-write: {err}")
    return ref


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", required=True, help="compiled scene (.lxs)")
    ap.add_argument("--models", nargs="+", required=True)
    ap.add_argument("--work-dir", required=True)
    ap.add_argument("--spp", type=int, nargs="+", default=[1, 4, 16, 64])
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--resolution", default="256x256")
    ap.add_argument("--feature-spp", type=int, default=int(config.preset_text("FEATURE_SPP")))
    ap.add_argument("--bin-dir", default="target/release", help="where trace, aov-write, denoise, evaluate are")
    args = ap.parse_args(argv)
    bins, work = Path(args.bin_dir).resolve(), Path(args.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    ref = render(args, bins, work)
    images, refused = [], {}
    for m, model in enumerate(args.models):
        for kind in FEATURE_SETS:
            out = work / f"model-{Path(model).stem}" / kind
            out.mkdir(parents=True, exist_ok=True)
            for spp in args.spp:
                hdr = contract.image_name(str(work / "scene"), "hdr", spp)
                dn = out / Path(contract.image_name("scene", "dn", spp))
                feats = [
                    a
                    for k in contract.FEATURES[1:]
                    for a in (f"--{k}", contract.image_name(str(work / kind / "scene"), k, spp))
                ]
                if not dn.exists() or dn.stat().st_mtime < Path(model).stat().st_mtime:
                    err = run([bins / "denoise", hdr, "--model", model, *feats, "-o", dn])
                    if err:
                        refused[(m, kind, spp)] = err
                        continue
                images.append(((m, kind, spp), dn))
    noisy = {spp: contract.image_name(str(work / "scene"), "hdr", spp) for spp in args.spp}
    scores = work / "scores.csv"
    err = run([bins / "evaluate", "images", "--reference", ref, *noisy.values(), *(p for _, p in images), "-o", scores])
    if err:
        sys.exit(f"compare_features: evaluate: {err}")
    with open(scores) as f:
        rows = {Path(r["image"]).resolve(): r for r in csv.DictReader(f)}
    value = lambda path, k: float(rows[Path(path).resolve()][k])
    for kind in FEATURE_SETS:
        print(f"\n{kind} features: PSNR dB / SSIM / FLIP at {' / '.join(map(str, args.spp))} spp")
        print("noisy: " + " | ".join(" / ".join(f"{value(noisy[s], k):.4g}" for s in args.spp) for k in METRICS))
        for m, model in enumerate(args.models):
            cells = []
            for k in METRICS:
                vals = []
                for s in args.spp:
                    path = dict(images).get((m, kind, s))
                    vals.append("refused" if path is None else f"{value(path, k):.4g}")
                cells.append(" / ".join(vals))
            print(f"{model}: " + " | ".join(cells))
    for (m, kind, spp), err in sorted(refused.items())[:3]:
        print(f"refused: {args.models[m]} with {kind} features at {spp} spp: {err}")


if __name__ == "__main__":
    main()
