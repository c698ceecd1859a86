"""`make bench-edges`: are the pixels on object edges of an image unbiased? Compares a test image
with an independent reference pixel by pixel, each with its standard-error image (luxest's
`.se.exr`, R = G = B = the standard error of Y), on the pixels where the reference changes by
more than 20 % from a 4-neighbour (object edges, where the double local estimate's kernel is
singular and its footprint matters), and on the rest. Per group: the ratio of the sums of Y
(test / reference) with its standard error, the mean z and mean z² of
z = (test − reference) / √(se_test² + se_ref²) (with standard errors from 8 batches, z follows
Student's t with 7 degrees of freedom: mean z² 7/5), and the share of pixels with |z| > 4."""

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
from luxest_contract import luminance, read_rgb  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from atomic import write_text  # noqa: E402

EDGE_CONTRAST = 0.2


def edge_mask(y):
    """Pixels whose value differs by more than EDGE_CONTRAST (relative) from a 4-neighbour."""
    c = np.zeros(y.shape, dtype=bool)
    for axis in (0, 1):
        for step in (1, -1):
            s = np.roll(y, step, axis)
            d = np.abs(s - y) / np.maximum(np.maximum(s, y), 1e-12)
            # np.roll wraps around: the image border has no neighbour there.
            if step == 1:
                d[(slice(0, 1) if axis == 0 else (slice(None), slice(0, 1)))] = 0
            else:
                d[(slice(-1, None) if axis == 0 else (slice(None), slice(-1, None)))] = 0
            c |= d > EDGE_CONTRAST
    return c


def group_stats(test, se_test, ref, se_ref, mask):
    n = int(mask.sum())
    se = np.hypot(se_test[mask], se_ref[mask])
    ok = se > 0
    z = (test[mask][ok] - ref[mask][ok]) / se[ok]
    ratio = test[mask].sum() / ref[mask].sum()
    # Pixels' errors are independent across pixels for the reference; the test's standard
    # error of the sum treats them as independent too (a lower bound for the double local
    # estimate, whose pixels share light paths).
    ratio_se = np.sqrt((se_test[mask] ** 2).sum() + (se_ref[mask] ** 2).sum()) / ref[mask].sum()
    return {
        "pixels": n,
        "ratio": ratio,
        "ratio_se": ratio_se,
        "mean_z": float(z.mean()),
        "mean_z2": float((z * z).mean()),
        "over4": float((np.abs(z) > 4).mean()),
        "no_se": int((~ok).sum()),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reference", required=True)
    ap.add_argument("--reference-se", required=True)
    ap.add_argument("--test", required=True, action="append", help="image (repeatable)")
    ap.add_argument("--test-se", required=True, action="append", help="its standard error (same order)")
    ap.add_argument("--label", action="append", help="a name per test image")
    ap.add_argument("-o", "--out", required=True, help="Markdown table")
    a = ap.parse_args(argv)
    if len(a.test) != len(a.test_se):
        sys.exit("error: give one --test-se per --test")
    ref = luminance(read_rgb(a.reference).astype(np.float64))
    se_ref = read_rgb(a.reference_se).astype(np.float64)[..., 0]
    edges = edge_mask(ref)
    lines = [
        f"Edge bias against `{a.reference}` (edges: {edges.sum()} of {edges.size} pixels differ by more "
        f"than {EDGE_CONTRAST:.0%} from a neighbour).",
        "",
        "| image | pixels | n | Y test / reference | mean z | mean z² (7/5 expected) | share of abs(z) > 4 |",
        "|---|---|---|---|---|---|---|",
    ]
    for i, (t, ts) in enumerate(zip(a.test, a.test_se)):
        test = luminance(read_rgb(t).astype(np.float64))
        se_test = read_rgb(ts).astype(np.float64)[..., 0]
        if test.shape != ref.shape:
            sys.exit(f"error: {t}: {test.shape[1]}x{test.shape[0]}, the reference is {ref.shape[1]}x{ref.shape[0]}")
        name = a.label[i] if a.label and i < len(a.label) else Path(t).name
        for group, mask in (("edges", edges), ("the rest", ~edges)):
            s = group_stats(test, se_test, ref, se_ref, mask)
            lines.append(
                f"| {name} | {group} | {s['pixels']} | {s['ratio']:.4f} ± {s['ratio_se']:.4f} | "
                f"{s['mean_z']:+.3f} | {s['mean_z2']:.2f} | {s['over4']:.4f} |"
            )
    write_text(a.out, "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
