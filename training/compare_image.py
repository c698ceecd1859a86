#!/usr/bin/env python3
"""PSNR and SSIM of noisy and denoised images against the references of a split, scored by the
`evaluate images` stage (--evaluate, the Makefile's EVALUATE) so that the words mean exactly what
they mean in `make eval`'s reports/summary.md: tonemapped with the reference's autoexposure,
Reinhard, sRGB OETF (crates/evaluate). Denoises with onnxruntime (infer.py) into --work-dir,
prints per level the mean over scenes and the gain of denoising; --json writes the numbers, per
level and per scene. With --oidn, Intel Open Image Denoise (pipelines/oidn_denoise.py, the peer of
`make eval`: hdr + albedo + normal) denoises the same inputs into --work-dir/oidn, is scored the
same way, and each level shows luxest's margin over it: the held-out comparison of `make eval` on
any split (a validation split to choose a model, a larger test split to measure one)."""

import argparse
import json
import subprocess
import sys
from pathlib import Path

import infer
import luxest_contract as contract
import progress

PIPELINES = Path(__file__).resolve().parents[1] / "pipelines"


def score(evaluate, reference, tests, out_csv):
    """Rows of `evaluate images` for tests against reference."""
    cmd = [str(evaluate), "images", "--reference", str(reference), *map(str, tests), "-o", str(out_csv)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"compare_image: {' '.join(cmd[:2])} failed: {(r.stderr or r.stdout).strip()}")
    return contract.read_image_report(out_csv)


def oidn_split(done, scan, work_dir):
    """OIDN's output for each denoised input of `done` (infer.denoise_split's list), with the
    features next to the input (`scan`: contract.scan of the split), into work_dir/oidn. Returns
    {noisy path: OIDN output path}."""
    if str(PIPELINES) not in sys.path:
        sys.path.insert(0, str(PIPELINES))
    import oidn_denoise

    out_dir = Path(work_dir) / "oidn"
    out_dir.mkdir(parents=True, exist_ok=True)
    outs = {}
    for name, spp, noisy, _ in done:
        feats = next(f for k, f in scan[name].items() if k is not None and Path(f["hdr"]) == Path(noisy))
        out = out_dir / contract.image_name(name, "dn", spp)
        oidn_denoise.main([str(noisy), "--alb", str(feats["alb"]), "--nrm", str(feats["nrm"]), "-o", str(out)])
        outs[str(noisy)] = out
    return outs


KEYS = ("psnr_noisy", "psnr_denoised", "ssim_noisy", "ssim_denoised", "psnr_oidn", "ssim_oidn")


def compare(model, split_dir, work_dir, evaluate, spp_levels, oidn=False):
    """({spp: {psnr_noisy, psnr_denoised, ssim_noisy, ssim_denoised[, psnr_oidn, ssim_oidn], scenes}}
    (means over scenes), {scene: {spp: the same, per scene}})."""
    work = Path(work_dir)
    scan = contract.scan(split_dir)
    refs = {name: levels[None]["hdr"] for name, levels in scan.items() if None in levels and "hdr" in levels[None]}
    missing = sorted(set(scan) - set(refs))
    if missing:
        raise contract.ContractError(
            f"{split_dir}: {', '.join(missing)} without a reference image (<scene>_ref.hdr.exr)"
        )
    done = infer.denoise_split(model, split_dir, work, spp_levels, scan)
    peer = oidn_split(done, scan, work) if oidn else {}
    keys = KEYS if oidn else KEYS[:4]
    per_level, per_scene = {}, {}
    names = sorted({d[0] for d in done})
    with progress.Progress("compare_image", len(names), "scenes") as shown:
        for name in names:
            mine = [d for d in done if d[0] == name]
            tests = [d[2] for d in mine] + [d[3] for d in mine] + [peer[str(d[2])] for d in mine if oidn]
            rows = score(evaluate, refs[name], tests, work / f"{name}.images.csv")
            by_image = {str(Path(r["image"]).resolve()): r for r in rows}
            row = lambda path: by_image[str(Path(path).resolve())]
            for _, spp, noisy, dn in mine:
                n, d = row(noisy), row(dn)
                vals = [n["psnr_db"], d["psnr_db"], n["ssim"], d["ssim"]]
                if oidn:
                    o = row(peer[str(noisy)])
                    vals += [o["psnr_db"], o["ssim"]]
                per_level.setdefault(spp, []).append(vals)
                per_scene.setdefault(name, {})[spp] = dict(zip(keys, vals))
            shown.update()
    summary = {}
    for spp, vals in sorted(per_level.items()):
        m = [sum(v[k] for v in vals) / len(vals) for k in range(len(keys))]
        summary[spp] = {**dict(zip(keys, m)), "scenes": len(vals)}
    return summary, per_scene


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--split-dir", required=True)
    ap.add_argument("--work-dir", required=True, help="denoised images and evaluate's reports")
    ap.add_argument("--evaluate", required=True, help="the evaluate stage binary (Makefile: EVALUATE)")
    ap.add_argument("--spp", type=int, nargs="+", default=[1, 4, 16, 64])
    ap.add_argument("--oidn", action="store_true", help="also denoise with OIDN 1.4.3 (PyPI oidn) and show the margin")
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    for what, f in (("--model", args.model), ("--evaluate", args.evaluate)):
        if not Path(f).is_file():
            sys.exit(f"compare_image: error: {what} {f}: not found")
    if not Path(args.split_dir).is_dir():
        sys.exit(f"compare_image: error: --split-dir {args.split_dir}: not a directory")
    try:
        summary, per_scene = compare(args.model, args.split_dir, args.work_dir, args.evaluate, args.spp, args.oidn)
    except contract.ContractError as e:
        sys.exit(f"compare_image: error: {e}")
    except ImportError as e:
        sys.exit(f"compare_image: error: --oidn needs PyPI oidn in this Python ({e})")
    head = f"{'spp':>5} {'scenes':>6} {'PSNR noisy':>11} {'PSNR denoised':>14} {'gain dB':>8} {'SSIM noisy':>11} {'SSIM denoised':>14}"
    print(head + (f" {'PSNR OIDN':>10} {'vs OIDN dB':>11} {'SSIM OIDN':>10}" if args.oidn else ""))
    for spp, m in summary.items():
        line = (
            f"{spp:>5} {m['scenes']:>6} {m['psnr_noisy']:>11.2f} {m['psnr_denoised']:>14.2f} "
            f"{m['psnr_denoised'] - m['psnr_noisy']:>8.2f} {m['ssim_noisy']:>11.4f} {m['ssim_denoised']:>14.4f}"
        )
        if args.oidn:
            line += f" {m['psnr_oidn']:>10.2f} {m['psnr_denoised'] - m['psnr_oidn']:>+11.2f} {m['ssim_oidn']:>10.4f}"
        print(line)
    if args.json:
        out = {
            "metrics": "evaluate images (crates/evaluate): tonemapped PSNR dB and SSIM, means over the split's scenes",
            "levels": {str(k): v for k, v in summary.items()},
            "scenes": {name: {str(k): v for k, v in levels.items()} for name, levels in per_scene.items()},
        }
        Path(args.json).write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
