"""Data flow of preprocessing: independent reference seeds, spp from headers, and the
whole-image exposure stored for training."""

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

TRAINING = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(TRAINING))

import dataset  # noqa: E402
import luxest_contract as contract  # noqa: E402
import preprocess  # noqa: E402


def write_set(split_dir, name, spp, seed, rng, h=32, w=48, file_spp=None):
    """One noisy level (hdr, alb, nrm, emi, ema) with the headers trace / aov-write record."""
    header = {contract.SAMPLES: spp, contract.SEED: seed, contract.ESTIMATOR: "path-tracing"}
    # A bright left half, a dim right half: a crop's own exposure differs from the image's.
    hdr = rng.random((h, w, 3)).astype(np.float32) * np.where(np.arange(w) < w // 2, 10.0, 0.1)[None, :, None].astype(
        np.float32
    )
    contract.write(split_dir / contract.image_name(name, "hdr", file_spp or spp), hdr, header)
    for kind in ("alb", "nrm", "emi", "ema"):
        contract.write(split_dir / contract.image_name(name, kind, file_spp or spp), rng.random((h, w, 3)), header)
    return hdr


def write_ref(split_dir, name, seed, rng, h=32, w=48):
    contract.write(
        split_dir / contract.image_name(name, "hdr"),
        rng.random((h, w, 3)),
        {contract.SAMPLES: 256, contract.SEED: seed},
    )


def test_refuses_a_reference_with_the_noisy_seed(tmp_path):
    rng = np.random.default_rng(1)
    src = tmp_path / "data" / "train"
    src.mkdir(parents=True)
    write_ref(src, "gen0000", 1, rng)
    write_set(src, "gen0000", 4, 1, rng)
    with pytest.raises(contract.ContractError) as e:
        preprocess.preprocess_split(src, tmp_path / "prep", [4])
    msg = str(e.value)
    assert "gen0000_ref.hdr.exr" in msg and "gen0000_000004spp.hdr.exr" in msg and f"{contract.SEED} = 1" in msg
    assert "\n" not in msg
    # The command line: exit 1, one line on stderr naming both files.
    for split in ("valid", "test"):
        (tmp_path / "data" / split).mkdir()
    r = subprocess.run(
        [
            sys.executable,
            str(TRAINING / "preprocess.py"),
            "--data-dir",
            str(tmp_path / "data"),
            "--prep-dir",
            str(tmp_path / "prep"),
            "--noisy-spp",
            "4",
        ],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1
    assert "gen0000_ref.hdr.exr" in r.stderr and "gen0000_000004spp.hdr.exr" in r.stderr


def test_spp_comes_from_the_header(tmp_path):
    rng = np.random.default_rng(2)
    src = tmp_path / "train"
    src.mkdir()
    write_ref(src, "g", 1000001, rng)
    write_set(src, "g", 8, 1, rng, file_spp=4)  # the name says 4, the header 8
    with pytest.raises(contract.ContractError, match=f"{contract.SAMPLES} = 8 but the file name says 4"):
        preprocess.preprocess_split(src, tmp_path / "prep", [4, 8])


def test_stores_the_whole_image_exposure_for_every_crop(tmp_path):
    rng = np.random.default_rng(3)
    src = tmp_path / "train"
    src.mkdir()
    write_ref(src, "g", 1000001, rng)
    h, w = 32, 48
    # Channel c is (c + 1) times a brightness that is 10 on the left half and 0.1 on the right,
    # so a crop's channel order shows its permutation, and its own exposure is not the image's.
    bright = np.where(np.arange(w) < w // 2, 10.0, 0.1)[None, :, None] * (1 + 0.2 * rng.random((h, w, 1)))
    hdr = (bright * np.array([1.0, 2.0, 3.0])).astype(np.float32)
    header = {contract.SAMPLES: 4, contract.SEED: 1}
    contract.write(src / contract.image_name("g", "hdr", 4), hdr, header)
    for kind in ("alb", "nrm"):
        contract.write(src / contract.image_name("g", kind, 4), rng.random((h, w, 3)), header)
    # The emission: half the radiance, its antialiased version a quarter, so each crop shows
    # whether they were flipped and permuted like the radiance.
    contract.write(src / contract.image_name("g", "emi", 4), 0.5 * hdr, header)
    contract.write(src / contract.image_name("g", "ema", 4), 0.25 * hdr, header)
    assert preprocess.preprocess_split(src, tmp_path / "prep", [4]) == 2
    [(inp, ref, meta)] = dataset.pairs(tmp_path / "prep")
    assert (meta["samples"], meta["seed"], meta["reference_seed"]) == (4, 1, 1000001)
    assert math.isclose(meta["exposures"][0], contract.exposure(hdr), rel_tol=1e-15)
    crops = dataset.Crops(tmp_path / "prep", crop=16, seed=5, length=40)
    reference = contract.read(src / contract.image_name("g", "hdr")).pixels[..., :3]
    seen, differs = set(), 0
    for i in range(len(crops)):
        a, b, e, e_ref = crops[i]
        assert a.shape[0] == 15 and torch.allclose(a[9:12], 0.5 * a[0:3], rtol=1e-6)
        assert torch.allclose(a[12:15], 0.25 * a[0:3], rtol=1e-6)
        perm = tuple(int(r) for r in np.argsort(np.argsort([float(a[j].mean()) for j in range(3)])))
        seen.add(perm)
        whole = contract.exposure(hdr[..., list(perm)])
        assert math.isclose(float(e), whole, rel_tol=1e-6)
        # The reference's whole-image exposure under the same permutation (loss.display's).
        assert math.isclose(float(e_ref), contract.exposure(reference[..., list(perm)]), rel_tol=1e-6)
        own = contract.exposure(a[0:3].permute(1, 2, 0).numpy())
        differs += not math.isclose(float(e), own, rel_tol=0.5)
    assert len(seen) > 1 and differs > len(crops) // 2  # a per-crop exposure would be wrong
    # Preprocessing is incremental: nothing to do the second time.
    assert preprocess.preprocess_split(src, tmp_path / "prep", [4]) == 0


def test_local_estimate_inputs_use_the_largest_noisy_levels_features(tmp_path):
    rng = np.random.default_rng(7)
    src = tmp_path / "train"
    src.mkdir()
    write_ref(src, "g", 1000001, rng)
    write_set(src, "g", 4, 1, rng)
    write_set(src, "g", 16, 1, rng)
    le = rng.random((32, 48, 3)).astype(np.float32)
    contract.write(
        src / contract.image_name("g", "hdr", 100, unit="le"),
        le,
        {contract.SAMPLES: 100, contract.SEED: 1, contract.ESTIMATOR: "double-local-estimate"},
    )
    # Levels not asked for are skipped: 4 spp and the local estimate at 100 paths are written.
    assert preprocess.preprocess_split(src, tmp_path / "prep", [4], [100]) == 3
    by_unit = {meta["unit"]: (inp, meta) for inp, _, meta in dataset.pairs(tmp_path / "prep")}
    inp, meta = by_unit["le"]
    assert inp.name == "g_000100le.npy" and meta["samples"] == 100
    assert meta["estimator"] == "double-local-estimate" and meta["features"] == "g_000016spp.alb.exr"
    arr = np.load(inp)
    np.testing.assert_array_equal(arr[..., 0:3], le)
    np.testing.assert_array_equal(arr[..., 3:6], contract.read_rgb(src / "g_000016spp.alb.exr"))
    assert meta["exposures"][0] == pytest.approx(contract.exposure(le))
    # A local estimate with the reference's seed is refused like a noisy level.
    contract.write(
        src / contract.image_name("g", "hdr", 300, unit="le"), le, {contract.SAMPLES: 300, contract.SEED: 1000001}
    )
    with pytest.raises(contract.ContractError, match="g_000300le.hdr.exr"):
        preprocess.preprocess_split(src, tmp_path / "prep", [4], [100, 300])


def test_refuses_a_reference_with_fewer_samples_than_its_input_and_mismatched_sizes(tmp_path):
    rng = np.random.default_rng(8)
    src = tmp_path / "train"
    src.mkdir()
    write_ref(src, "g", 1000001, rng)  # 256 spp
    write_set(src, "g", 1024, 1, rng)
    with pytest.raises(contract.ContractError, match="256 samples per pixel, fewer than its input"):
        preprocess.preprocess_split(src, tmp_path / "prep", [1024])
    src2 = tmp_path / "valid"
    src2.mkdir()
    write_ref(src2, "g", 1000001, rng)
    write_set(src2, "g", 4, 1, rng, h=32, w=40)
    with pytest.raises(
        contract.ContractError, match=r"g_000004spp.hdr.exr: 40x32 pixels, its reference g_ref.hdr.exr 48x32"
    ):
        preprocess.preprocess_split(src2, tmp_path / "prep2", [4])


def test_training_pairs_follow_the_configured_levels(tmp_path):
    # Arrays an earlier configuration left in the directory are not trained on.
    rng = np.random.default_rng(9)
    src = tmp_path / "train"
    src.mkdir()
    write_ref(src, "g", 1000001, rng)
    for spp in (4, 16):
        write_set(src, "g", spp, 1, rng)
    contract.write(
        src / contract.image_name("g", "hdr", 100, unit="le"),
        rng.random((32, 48, 3)),
        {contract.SAMPLES: 100, contract.SEED: 1},
    )
    preprocess.preprocess_split(src, tmp_path / "prep", [4, 16], [100])
    tags = lambda ps: sorted(p[0].name for p in ps)
    assert tags(dataset.pairs(tmp_path / "prep")) == ["g_000004spp.npy", "g_000016spp.npy", "g_000100le.npy"]
    assert tags(dataset.pairs(tmp_path / "prep", [16], [])) == ["g_000016spp.npy"]
    assert tags(dataset.pairs(tmp_path / "prep", [4], [100])) == ["g_000004spp.npy", "g_000100le.npy"]


def test_features_follow_the_configuration(tmp_path):
    # A dataset rendered before aov-write wrote the emission is refused for an emission model,
    # naming what is missing and how to get it; a three-feature configuration takes it, and
    # switching the configuration redoes the arrays (they record their channels).
    rng = np.random.default_rng(9)
    src = tmp_path / "train"
    src.mkdir()
    write_ref(src, "g", 1000001, rng)
    write_set(src, "g", 4, 1, rng)
    (src / contract.image_name("g", "emi", 4)).unlink()
    with pytest.raises(contract.ContractError, match="g at 4 spp lacks emi .*make noisy reference"):
        preprocess.preprocess_split(src, tmp_path / "prep", [4])
    assert preprocess.preprocess_split(src, tmp_path / "prep", [4], features=contract.FEATURES[:3]) == 2
    [(inp, _, meta)] = dataset.pairs(tmp_path / "prep")
    assert np.load(inp).shape[-1] == 9 and meta["channels"] == ["hdr", "alb", "nrm"]
    contract.write(
        src / contract.image_name("g", "emi", 4), rng.random((32, 48, 3)), {contract.SAMPLES: 4, contract.SEED: 1}
    )
    assert preprocess.preprocess_split(src, tmp_path / "prep", [4], features=contract.FEATURES[:4]) == 1
    [(inp, _, meta)] = dataset.pairs(tmp_path / "prep")
    assert np.load(inp).shape[-1] == 12 and meta["channels"] == list(contract.FEATURES[:4])
    # The antialiased emission: all five (the default).
    assert preprocess.preprocess_split(src, tmp_path / "prep", [4]) == 1
    [(inp, _, meta)] = dataset.pairs(tmp_path / "prep")
    assert np.load(inp).shape[-1] == 15 and meta["channels"] == list(contract.FEATURES)


def write_realization(split_dir, name, spp, seed, rng, header_seed=None):
    """write_set into the realization directory of `seed`, with that seed in the headers unless
    `header_seed` says otherwise."""
    d = split_dir / contract.REALIZATION_DIR.format(seed=seed)
    d.mkdir(exist_ok=True)
    return write_set(d, name, spp, seed if header_seed is None else header_seed, rng)


def test_extra_noise_realizations_pair_with_their_scenes_reference(tmp_path):
    rng = np.random.default_rng(11)
    src, prep = tmp_path / "train", tmp_path / "prep"
    src.mkdir()
    for name in ("a", "b"):
        write_ref(src, name, 1000001, rng)
        for spp in (1, 4):
            write_set(src, name, spp, 1, rng)
    hdr = {k: write_realization(src, "a", 1, k, rng) for k in (2, 3)}
    write_realization(src, "a", 4, 2, rng)
    # Only the seeds asked for, and only the configured levels.
    assert preprocess.preprocess_split(src, prep, [1, 4], extra_seeds=[3]) == 4 + 2 + 1
    assert preprocess.preprocess_split(src, prep, [1, 4], extra_seeds=[2, 3], extra_spp=[1]) == 1
    found = dataset.pairs(prep, [1, 4], extra_seeds=[2, 3])
    rel = lambda p: str(p.relative_to(prep))
    assert [rel(i) for i, _, _ in found] == [
        "a_000001spp.npy",
        "a_000004spp.npy",
        "b_000001spp.npy",
        "b_000004spp.npy",
        "seed2/a_000001spp.npy",
        "seed3/a_000001spp.npy",
    ]
    assert all(rel(r) == f"{m['name']}_ref.npy" for _, r, m in found)
    for i, _, m in found[4:]:
        k = int(i.parent.name[4:])
        assert (m["seed"], m["reference_seed"]) == (k, 1000001)
        assert np.array_equal(np.load(i)[..., :3], hdr[k])
        assert math.isclose(m["exposures"][0], contract.exposure(hdr[k]), rel_tol=1e-15)
    # Without seeds, no realization; only the realizations' levels (arrays of a level no longer
    # among them are left alone); a scene's level and its realizations form one group.
    assert len(dataset.pairs(prep, [1, 4])) == 4
    assert len(dataset.pairs(prep, [1, 4], extra_seeds=[2, 3], extra_spp=[4])) == 4
    assert preprocess.preprocess_split(src, prep, [1, 4], extra_seeds=[2], extra_spp=[4]) == 1
    assert [str(i.relative_to(prep)) for i, _, _ in dataset.pairs(prep, [1, 4], extra_seeds=[2, 3], extra_spp=[4])][
        4:
    ] == ["seed2/a_000004spp.npy"]
    assert dataset.groups([m for *_, m in found]) == [[0, 4, 5], [1], [2], [3]]


def test_refuses_a_realization_without_a_seed_of_its_own(tmp_path):
    rng = np.random.default_rng(12)
    src = tmp_path / "train"
    src.mkdir()
    write_ref(src, "a", 1000001, rng)
    write_set(src, "a", 1, 1, rng)
    with pytest.raises(contract.ContractError, match=r"seed2: no such directory .*make noisy"):
        preprocess.preprocess_split(src, tmp_path / "prep", [1], extra_seeds=[2])
    # A header seed that is not the directory's, the split's own seed, the reference's seed.
    write_realization(src, "a", 1, 2, rng, header_seed=5)
    with pytest.raises(contract.ContractError, match=r"a_000001spp.hdr.exr: luxest.seed = 5 in a directory of seed 2"):
        preprocess.preprocess_split(src, tmp_path / "prep", [1], extra_seeds=[2])
    write_realization(src, "a", 1, 1, rng)
    with pytest.raises(
        contract.ContractError, match=r"the same luxest.seed = 1 \(a realization must have a seed of its own\)"
    ):
        preprocess.preprocess_split(src, tmp_path / "prep", [1], extra_seeds=[1])
    write_realization(src, "a", 1, 1000001, rng)
    with pytest.raises(contract.ContractError, match=r"reference and noisy image share luxest.seed = 1000001"):
        preprocess.preprocess_split(src, tmp_path / "prep", [1], extra_seeds=[1000001])
    # A realization of a scene the split has no reference for.
    write_realization(src, "z", 1, 3, rng)
    with pytest.raises(contract.ContractError, match=r"seed3: z has no reference image in"):
        preprocess.preprocess_split(src, tmp_path / "prep", [1], extra_seeds=[3])


def test_crops_draw_a_scenes_level_then_one_of_its_realizations(tmp_path):
    rng = np.random.default_rng(13)
    src, prep = tmp_path / "train", tmp_path / "prep"
    src.mkdir()
    for name in ("a", "b"):
        write_ref(src, name, 1000001, rng)
        write_set(src, name, 1, 1, rng)
    for k in (2, 3, 4):
        write_realization(src, "a", 1, k, rng)
    preprocess.preprocess_split(src, prep, [1], extra_seeds=[2, 3, 4])
    # Without realizations, crop i is drawn exactly as before they existed: pair, top, left,
    # three flips and a permutation from default_rng((seed, i)).
    plain = dataset.Crops(prep, crop=16, seed=5, length=50)
    for i in range(50):
        r = np.random.default_rng((5, i))
        p = int(r.integers(2))
        y, x = int(r.integers(0, 32 - 16 + 1)), int(r.integers(0, 48 - 16 + 1))
        flips = tuple(bool(r.random() < 0.5) for _ in range(3))
        assert plain.draw(i) == (p, y, x, *flips, int(r.integers(6)))
    # With three realizations of a: a and b equally often (a binomial mean, 4 standard errors),
    # and a's four images each a quarter of a's draws.
    crops = dataset.Crops(prep, crop=16, seed=5, length=8000, extra_seeds=[2, 3, 4])
    assert len(crops.pairs) == 5 and crops.groups == [[0, 2, 3, 4], [1]]
    counts = np.bincount([crops.draw(i)[0] for i in range(8000)], minlength=5)
    n_a = counts[[0, 2, 3, 4]].sum()
    assert abs(n_a / 8000 - 0.5) < 4 * math.sqrt(0.25 / 8000)
    for p in (0, 2, 3, 4):
        assert abs(counts[p] / n_a - 0.25) < 4 * math.sqrt(0.25 * 0.75 / n_a)


def write_own(split_dir, name, spp, seed, rng, samples=None):
    """The features of level `spp` at its own sample count in `<split>/own/` (aov-write
    --min-samples 1), with `samples` in their headers (default: the level's); returns the albedo."""
    d = split_dir / contract.OWN_FEATURES_DIR
    d.mkdir(exist_ok=True)
    header = {contract.SAMPLES: samples or spp, contract.SEED: seed}
    planes = {}
    for kind in ("alb", "nrm", "emi", "ema"):
        planes[kind] = rng.random((32, 48, 3)).astype(np.float32)
        contract.write(d / contract.image_name(name, kind, spp), planes[kind], header)
    return planes["alb"]


def test_own_sample_features_pair_with_the_splits_radiance_and_group_with_it(tmp_path):
    rng = np.random.default_rng(21)
    src, prep = tmp_path / "train", tmp_path / "prep"
    src.mkdir()
    write_ref(src, "a", 1000001, rng)
    hdr = {spp: write_set(src, "a", spp, 1, rng) for spp in (1, 4, 16)}
    alb = {spp: write_own(src, "a", spp, 1, rng) for spp in (1, 4)}
    # Not asked for: none written; asked for: the two own-feature inputs beside the three.
    assert preprocess.preprocess_split(src, prep, [1, 4, 16]) == 3 + 1
    assert preprocess.preprocess_split(src, prep, [1, 4, 16], own_features=True) == 2
    assert len(dataset.pairs(prep, [1, 4, 16])) == 3
    found = dataset.pairs(prep, [1, 4, 16], own_features=True)
    rel = [str(i.relative_to(prep)) for i, _, _ in found]
    assert rel[3:] == ["own/a_000001spp.npy", "own/a_000004spp.npy"]
    for (i, r, m), spp in zip(found[3:], (1, 4)):
        arr = np.load(i)
        # The split's radiance of the level (the same samples), the own albedo, the scene's reference.
        assert np.array_equal(arr[..., :3], hdr[spp]) and np.array_equal(arr[..., 3:6], alb[spp])
        assert r == prep / "a_ref.npy" and m["samples"] == spp
    # One group per (scene, level): each own input draws against its antialiased twin.
    assert dataset.groups([m for *_, m in found]) == [[0, 3], [1, 4], [2]]


def test_refuses_own_features_of_another_sample_count(tmp_path):
    rng = np.random.default_rng(22)
    src = tmp_path / "train"
    src.mkdir()
    write_ref(src, "a", 1000001, rng)
    write_set(src, "a", 4, 1, rng)
    write_own(src, "a", 4, 1, rng, samples=16)
    with pytest.raises(contract.ContractError, match=r"own/a_000004spp.alb.exr: luxest.samples = 16, its radiance"):
        preprocess.preprocess_split(src, tmp_path / "prep", [4], own_features=True)
    write_own(src, "a", 4, 1, rng)
    write_own(src, "a", 8, 1, rng)
    with pytest.raises(contract.ContractError, match=r"a at 8 spp has no radiance image"):
        preprocess.preprocess_split(src, tmp_path / "prep", [4, 8], own_features=True)


@pytest.mark.parametrize("factor", [2.0**-12, 2.0**-3, 2.0**5, 2.0**20])
def test_crops_of_images_differing_by_a_power_of_two_are_the_same_with_a_mean_luminance(tmp_path, factor):
    """With MEAN_LUMINANCE the input and its reference are scaled into [v, 2 v) (range_exponent):
    an image and its copy times a power of two, bright or dim, give the same crops, exposures and
    reference exposures to the bit."""
    data = {}
    for tag, f in (("one", 1.0), ("scaled", factor)):
        src, prep = tmp_path / tag / "train", tmp_path / tag / "prep"
        src.mkdir(parents=True)
        r = np.random.default_rng(24)
        write_ref(src, "a", 1000001, r)
        write_set(src, "a", 4, 1, r)
        for p in src.glob("*.exr"):  # the radiance times f: hdr, emi, ema and the reference
            kind = p.name.split(".")[-2]
            if kind in contract.RADIANCE_FEATURES:
                img = contract.read(p)
                contract.write(p, (img.pixels.astype(np.float64) * f).astype(np.float32), dict(img.header))
        preprocess.preprocess_split(src, prep, [4])
        data[tag] = dataset.Crops(prep, crop=16, seed=3, length=20, mean_luminance=0.0625)
    one, scaled = data["one"], data["scaled"]
    assert one.scales[0] != 1.0  # the test image is brighter than the range: it is scaled
    assert scaled.scales[0] == one.scales[0] / factor
    for i in range(20):
        for u, v in zip(one[i], scaled[i]):
            assert torch.equal(u, v)
