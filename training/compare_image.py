#!/usr/bin/env python3
"""PSNR and SSIM of noisy and denoised images against the references of a split, scored by the
`evaluate images` stage (--evaluate, the Makefile's EVALUATE) so that the words mean exactly what
they mean in `make eval`'s reports/summary.md: tonemapped with the reference's autoexposure,
Reinhard, sRGB OETF (crates/evaluate). Denoises with onnxruntime (infer.py) into --work-dir,
prints per level the mean over scenes and the gain of denoising; --json writes the numbers."""
import argparse
import json
import subprocess
import sys
from pathlib import Path

import infer
import luxest_contract as contract


def score(evaluate, reference, tests, out_csv):
    """Rows of `evaluate images` for tests against reference."""
    cmd = [str(evaluate), "images", "--reference", str(reference), *map(str, tests), "-o", str(out_csv)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"compare_image: {' '.join(cmd[:2])} failed: {(r.stderr or r.stdout).strip()}")
    return contract.read_image_report(out_csv)


def compare(model, split_dir, work_dir, evaluate, spp_levels):
    """{spp: {psnr_noisy, psnr_denoised, ssim_noisy, ssim_denoised, scenes}} (means over scenes)."""
    work = Path(work_dir)
    done = infer.denoise_split(model, split_dir, work, spp_levels)
    refs = {name: levels[None]["hdr"] for name, levels in contract.scan(split_dir).items() if None in levels}
    per_level = {}
    for name in sorted({d[0] for d in done}):
        mine = [d for d in done if d[0] == name]
        rows = score(evaluate, refs[name], [d[2] for d in mine] + [d[3] for d in mine], work / f"{name}.images.csv")
        by_image = {Path(r["image"]).name: r for r in rows}
        for _, spp, noisy, dn in mine:
            n, d = by_image[Path(noisy).name], by_image[Path(dn).name]
            per_level.setdefault(spp, []).append([n["psnr_db"], d["psnr_db"], n["ssim"], d["ssim"]])
    summary = {}
    for spp, vals in sorted(per_level.items()):
        m = [sum(v[k] for v in vals) / len(vals) for k in range(4)]
        summary[spp] = {"psnr_noisy": m[0], "psnr_denoised": m[1], "ssim_noisy": m[2], "ssim_denoised": m[3], "scenes": len(vals)}
    return summary


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--split-dir", required=True)
    ap.add_argument("--work-dir", required=True, help="denoised images and evaluate's reports")
    ap.add_argument("--evaluate", required=True, help="the evaluate stage binary (Makefile: EVALUATE)")
    ap.add_argument("--spp", type=int, nargs="+", default=[1, 4, 16, 64])
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    summary = compare(args.model, args.split_dir, args.work_dir, args.evaluate, args.spp)
    print(f"{'spp':>5} {'scenes':>6} {'PSNR noisy':>11} {'PSNR denoised':>14} {'gain dB':>8} {'SSIM noisy':>11} {'SSIM denoised':>14}")
    for spp, m in summary.items():
        print(f"{spp:>5} {m['scenes']:>6} {m['psnr_noisy']:>11.2f} {m['psnr_denoised']:>14.2f} "
              f"{m['psnr_denoised'] - m['psnr_noisy']:>8.2f} {m['ssim_noisy']:>11.4f} {m['ssim_denoised']:>14.4f}")
    if args.json:
        out = {"metrics": "evaluate images (crates/evaluate): tonemapped PSNR dB and SSIM, means over the split's scenes",
               "levels": {str(k): v for k, v in summary.items()}}
        Path(args.json).write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
