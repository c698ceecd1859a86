"""The arithmetic of pipelines/eval.py (make eval): Pareto fronts and threshold crossing times."""

import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "pipelines"))
import eval as ev  # noqa: E402


def test_pareto_front_keeps_only_undominated_points():
    pts = [(1.0, 0.5, "a"), (2.0, 0.6, "b"), (2.0, 0.3, "c"), (3.0, 0.3, "d"), (4.0, 0.1, "e"), (0.5, 0.9, "f")]
    assert [p[2] for p in ev.pareto(pts)] == ["f", "a", "c", "e"]


def test_front_text_groups_runs_of_one_estimator():
    front = [(0.1, 1.0, "pt 1"), (0.2, 0.5, "pt 2"), (0.3, 0.4, "dn 1"), (4.0, 0.1, "pt 64")]
    assert ev.front_text(front) == "pt 1–2 (0.1–0.2 s) → dn 1 (0.3 s) → pt 64 (4 s)"


def test_crossing_time_interpolates_in_log_time():
    rows = [{"total_seconds": 1.0, "ssim": 0.90}, {"total_seconds": 4.0, "ssim": 0.96}]
    t, _ = ev.crossing_time(rows, 0.93)
    assert math.isclose(t, 2.0, rel_tol=1e-12)  # halfway in SSIM = halfway in log time
    assert ev.crossing_time(rows, 0.99) is None
    assert ev.crossing_time(rows, 0.5)[0] == 1.0


def test_extrapolation_follows_a_power_law_and_refuses_plateaus():
    # 1 - SSIM = 0.1 * t^-0.5: reaches 0.02 at t = 25.
    rows = [{"total_seconds": t, "ssim": 1 - 0.1 * t**-0.5} for t in (1.0, 2.0, 4.0, 8.0)]
    t, slope = ev.extrapolated_time(rows, 0.98)
    assert math.isclose(slope, -0.5, rel_tol=1e-9) and math.isclose(t, 25.0, rel_tol=1e-9)
    flat = [{"total_seconds": t, "ssim": 0.9 + 1e-4 * t} for t in (1.0, 2.0, 4.0, 8.0)]
    assert ev.extrapolated_time(flat, 0.98) is None


def test_colour_shift_is_the_largest_relative_channel_mean_error(tmp_path):
    import numpy as np
    import luxest_contract as contract

    rng = np.random.default_rng(1)
    ref = rng.random((8, 12, 3)).astype(np.float32) + 0.5
    img = ref * np.array([1.0, 0.98, 1.03], dtype=np.float32)  # blue +3 %, green −2 %
    contract.write(tmp_path / "r.hdr.exr", ref)
    contract.write(tmp_path / "i.hdr.exr", img)
    assert math.isclose(ev.colour_shift(tmp_path / "i.hdr.exr", tmp_path / "r.hdr.exr"), 0.03, rel_tol=1e-5)
    assert ev.colour_shift(tmp_path / "r.hdr.exr", tmp_path / "r.hdr.exr") == 0.0
    assert ev.colour_shift(tmp_path / "missing.exr", tmp_path / "r.hdr.exr") is None


def test_the_held_out_gap_is_paired_scene_by_scene():
    import numpy as np
    import pytest

    rng = np.random.default_rng(7)
    scenes, levels = ["a", "b", "c", "d", "e"], [4, 1, 16]
    ours, theirs = rng.normal(33, 2, (3, 5)), rng.normal(32, 2, (3, 5))
    rows = [
        {"estimator": e, "samples": n, "scene": s, "psnr_db": v[i, j]}
        for e, v in (("path-tracing+denoise", ours), ("path-tracing+oidn", theirs))
        for i, n in enumerate(levels)
        for j, s in enumerate(scenes)
        if not (n == 16 and s == "c" and e.endswith("oidn"))
    ]
    rows.append({"estimator": "path-tracing+oidn", "samples": 64, "scene": "a", "psnr_db": 1.0})  # no luxest row
    # The noisy input: not a denoiser.
    rows.append({"estimator": "path-tracing", "samples": 1, "scene": "a", "psnr_db": 9.0})
    rows = [rows[k] for k in rng.permutation(len(rows))]
    gaps = ev.paired_gaps(rows, "path-tracing")
    assert [n for n, *_ in gaps] == [1, 4, 16]  # increasing; 64 has no pair
    for n, d, missing in gaps:
        i = levels.index(n)
        keep = [j for j, s in enumerate(scenes) if not (n == 16 and s == "c")]
        diff = (ours[i] - theirs[i])[keep]
        assert list(d) == [scenes[j] for j in keep] and missing == (["c"] if n == 16 else [])
        assert np.allclose(list(d.values()), diff, rtol=0, atol=1e-12)
        mean, se, lo, hi, ahead = ev.gap_stats(d.values())
        assert math.isclose(mean, diff.mean(), abs_tol=1e-12)
        assert math.isclose(se, diff.std(ddof=1) / math.sqrt(len(diff)), rel_tol=1e-12)
        assert (lo, hi, ahead) == (diff.min(), diff.max(), int((diff > 0).sum()))
    assert ev.gap_stats([0.5])[1] is None
    lines = "\n".join(ev.gap_table(rows, scenes)).splitlines()
    d1 = ours[1] - theirs[1]  # level 1
    row = next(line for line in lines if line.startswith("| 1 |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells == [
        "1",
        f"{d1.mean():+.2f} ± {d1.std(ddof=1) / math.sqrt(5):.2f}",
        f"{d1.min():+.2f} … {d1.max():+.2f}",
        f"{int((d1 > 0).sum())} of 5",
        "yes" if d1.mean() >= 1 else "no",
        " / ".join(f"{x:+.2f}" for x in d1),
    ]
    assert "- 16 spp: without c (scored by one denoiser only, or not finite)" in lines
    assert not any("double-local-estimate" in line for line in lines)  # no such rows
    # A non-finite difference (both images identical to the reference) leaves the scene out.
    inf = [dict(r, psnr_db=math.inf) if r["scene"] == "e" and r["samples"] == 4 else r for r in rows]
    assert next(m for n, _, m in ev.paired_gaps(inf, "path-tracing") if n == 4) == ["e"]
    with pytest.raises(SystemExit, match=r"^eval: scene a: two path-tracing\+oidn rows at 64$"):
        ev.paired_gaps(rows + [rows[[r["samples"] for r in rows].index(64)]], "path-tracing")


def test_peer_table_shows_both_denoisers_inference_seconds_per_megapixel(tmp_path):
    import numpy as np
    import luxest_contract as contract

    paths = {}
    for name, wall, cpu in (
        ("noisy", None, None),
        ("ours", 0.004, 0.006),
        ("oidn", 0.005, 0.009),
        ("swapped", 0.002, None),
    ):
        head = {
            k: v for k, v in ((contract.DENOISE_SECONDS, wall), (contract.DENOISE_CPU_SECONDS, cpu)) if v is not None
        }
        paths[name] = tmp_path / f"{name}.exr"
        contract.write(paths[name], np.full((50, 40, 3), 0.5, np.float32), head)  # 2000 pixels
    assert ev.denoise_costs(str(paths["ours"])) == (0.004 / 0.002, 0.006 / 0.002)
    assert ev.denoise_costs(str(paths["swapped"])) == (1.0, None)
    assert ev.denoise_costs(str(tmp_path / "gone.exr")) == (None, None)
    row = lambda est, image: {
        "estimator": est,
        "samples": 4,
        "image": str(paths[image]),
        "psnr_db": 30.0,
        "ssim": 0.9,
        "flip": 0.1,
        "reference": str(paths["noisy"]),
    }
    rows = [row("path-tracing", "noisy"), row("path-tracing+denoise", "ours"), row("path-tracing+oidn", "oidn")]
    line = next(x for x in "\n".join(ev.peer_table(rows, "Cornell box 256²")).splitlines() if x.startswith("| 4 |"))
    cells = [c.strip() for c in line.strip("|").split("|")]
    assert cells[4:6] == ["2000 / 2500", "3.00 / 4.50"]  # ms and CPU-s per megapixel, luxest / OIDN
    rows[1] = row("path-tracing+denoise", "swapped")
    line = next(x for x in "\n".join(ev.peer_table(rows, "Cornell box 256²")).splitlines() if x.startswith("| 4 |"))
    assert [c.strip() for c in line.strip("|").split("|")][4:6] == ["1000 / 2500", "— / 4.50"]
    # Held-out rows are means over scenes with the costs stored (a scene without them: None).
    mean = lambda est, costs: {
        "estimator": est,
        "samples": 4,
        "psnr_db": 30.0,
        "ssim": 0.9,
        "flip": 0.1,
        "colour_shift": 0.01,
        "denoise_costs": costs,
    }
    rows = [
        mean("path-tracing", (None, None)),
        mean("path-tracing+denoise", (0.25, 0.5)),
        mean("path-tracing+oidn", (None, 0.75)),
    ]
    line = next(
        x for x in "\n".join(ev.peer_table(rows, "held-out scenes, mean over 2")).splitlines() if x.startswith("| 4 |")
    )
    assert [c.strip() for c in line.strip("|").split("|")][4:6] == ["250 / —", "0.50 / 0.75"]
    assert ev.mean_or_none([1.0, 3.0]) == 2.0 and ev.mean_or_none([1.0, None]) is None and ev.mean_or_none([]) is None


def test_texture_mask_is_the_albedo_luminance_local_deviation():
    # Against a direct computation: for each pixel, the standard deviation of the albedo's
    # luminance over the (2r + 1)² window clipped at the border, compared with TEXTURE_STD.
    import numpy as np

    rng = np.random.default_rng(3)
    albedo = np.full((20, 30, 3), 0.5)
    albedo[5:12, 8:20] = rng.random((7, 12, 3))  # a texture patch on a flat wall
    albedo[15:, 25:] = [0.1, 0.1, 0.1]  # a flat darker patch: its edge is in the mask
    y = albedo @ np.array([0.2126, 0.7152, 0.0722])
    r = ev.TEXTURE_RADIUS
    want = np.array(
        [
            [y[max(i - r, 0) : i + r + 1, max(j - r, 0) : j + r + 1].std() >= ev.TEXTURE_STD for j in range(30)]
            for i in range(20)
        ]
    )
    mask = ev.texture_mask(albedo)
    assert mask.shape == (20, 30) and np.array_equal(mask, want)
    assert mask[8, 14] and not mask[0, 0] and mask[15, 25]  # texture and an edge in, flat wall out
    assert not ev.texture_mask(np.full((9, 9, 3), 0.3)).any()


def test_the_bar_tables_compare_with_oidn_2_5_1(tmp_path):
    # gap_table and peer_table name OIDN 2.5.1 and score against its rows (+oidn2) when a report
    # has them; with 1.4.3's rows alone they are as before.
    rows = [
        {"estimator": e, "samples": n, "scene": s, "psnr_db": v}
        for n in (1, 4)
        for s, off in (("a", 0.0), ("b", 1.0))
        for e, v in (
            ("path-tracing+denoise", 30 + off),
            ("path-tracing+oidn", 29 + off),
            ("path-tracing+oidn2", 30.5 + off),
        )
    ]
    lines = "\n".join(ev.gap_table(rows, ["a", "b"])).splitlines()
    assert any("luxest − OIDN 2.5.1" in x for x in lines)
    row = next(x for x in lines if x.startswith("| 1 |"))
    assert [c.strip() for c in row.strip("|").split("|")][1] == "-0.50 ± 0.00"
    old = [r for r in rows if not r["estimator"].endswith("oidn2")]
    row = next(x for x in "\n".join(ev.gap_table(old, ["a", "b"])).splitlines() if x.startswith("| 1 |"))
    assert [c.strip() for c in row.strip("|").split("|")][1] == "+1.00 ± 0.00"
