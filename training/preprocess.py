#!/usr/bin/env python3
"""Converts a rendered dataset (data/<dataset>/<split>/*.exr) into float32 arrays for training:
inputs (H, W, 3 x features) = hdr + alb + nrm (+ emi [+ ema]: Config.features) per noisy level and per double-local-estimate image (`le`,
with the features of the largest noisy level), references (H, W, 3), and per input a JSON of its
samples, seeds and whole-image exposures (dataset.py). Incremental.

Samples and seeds come from the EXR headers (luxest_contract), not from file names. A pair whose
reference has the noisy image's seed is refused: a sample depends only on (seed, pixel, sample
index), so such a reference would contain the input's samples and the target would be
correlated with its input."""

import functools
import json
import sys
from pathlib import Path

import numpy as np

import config
import dataset
import luxest_contract as contract
import progress


def check_pair(ref, noisy):
    """ContractError unless the reference and the noisy hdr image have different seeds."""
    r, n = ref.value(contract.SEED, required=True), noisy.value(contract.SEED, required=True)
    if r == n:
        raise contract.ContractError(
            f"{ref.path} and {noisy.path}: reference and noisy image share {contract.SEED} = {r} "
            "(the reference must be rendered with an independent seed)"
        )


def samples_of(image, expected):
    """The image's samples from its header; an error if the file name says otherwise."""
    spp = image.value(contract.SAMPLES, required=True)
    if expected is not None and spp != expected:
        raise contract.ContractError(
            f"{image.path}: header {contract.SAMPLES} = {spp} but the file name says {expected}"
        )
    return spp


def preprocess_split(
    src, dst, noisy_spp, dle_paths=(), features=contract.FEATURES, extra_seeds=(), extra_spp=None, own_features=False
):
    """Writes the arrays of one split directory; returns the number written. Inputs: the noisy
    levels in `noisy_spp`, and the double-local-estimate images at `dle_paths` light paths
    (with the features of the scene's largest noisy level, as make eval denoises them), and the
    extra noise realizations of seeds `extra_seeds` (`<src>/seed<k>/`) at the noisy levels in
    `extra_spp` (None: all), and with `own_features` the noisy levels with the features of their
    own sample count (`<src>/own/`, the split's radiance of the level) into `<dst>/own/`."""
    n = 0
    dst.mkdir(parents=True, exist_ok=True)
    scenes = contract.scan(src)
    local_estimates = contract.scan(src, unit="le")
    realized = _realizations(src, scenes, extra_seeds)
    own_dir = src / contract.OWN_FEATURES_DIR
    own = contract.scan(own_dir) if own_features and own_dir.is_dir() else {}
    with progress.Progress(f"preprocess {src.name}", len(scenes), "scenes") as shown:
        for name, levels in scenes.items():
            if None not in levels or "hdr" not in levels[None]:
                raise contract.ContractError(f"{src}: {name} has no reference image")
            ref = contract.read(levels[None]["hdr"])
            ref_out = dst / dataset.prep_name(name, None)
            inputs = []  # (noisy hdr path, feature paths, count, unit)
            for spp_in_name, feats in sorted((k, v) for k, v in levels.items() if k is not None):
                _require_features(src, name, spp_in_name, feats, features)
                inputs.append((feats["hdr"], feats, spp_in_name, "spp"))
            for paths, kinds in sorted(local_estimates.get(name, {}).items()):
                if "hdr" not in kinds:
                    continue
                if not inputs:
                    raise contract.ContractError(
                        f"{kinds['hdr']}: {name} has no noisy level whose features it could use"
                    )
                inputs.append((kinds["hdr"], inputs[-1][1], paths, "le"))
            for hdr_path, feats, count_in_name, unit in inputs:
                n += _write_input(
                    dst,
                    name,
                    ref,
                    levels[None]["hdr"],
                    hdr_path,
                    feats,
                    count_in_name,
                    unit,
                    noisy_spp,
                    dle_paths,
                    features,
                )
            # The scene's extra noise realizations: its own reference, into <dst>/seed<k>/.
            for k, (sub, found) in realized.items():
                for count, feats in sorted((c, v) for c, v in found.get(name, {}).items() if c is not None):
                    if not (
                        dataset.wanted("spp", count, noisy_spp, None) and (extra_spp is None or count in extra_spp)
                    ):
                        continue
                    _require_features(sub, name, count, feats, features)
                    check = functools.partial(_check_realization, seed=k, twin=levels.get(count, {}).get("hdr"))
                    n += _write_input(
                        dst / sub.name,
                        name,
                        ref,
                        levels[None]["hdr"],
                        feats["hdr"],
                        feats,
                        count,
                        "spp",
                        noisy_spp,
                        (),
                        features,
                        check,
                    )
            # The levels with the features of their own samples: the split's radiance of the level.
            for count, feats in sorted((c, v) for c, v in own.get(name, {}).items() if c is not None):
                if count not in levels or "hdr" not in levels[count]:
                    raise contract.ContractError(f"{own_dir}: {name} at {count} spp has no radiance image in {src}")
                feats = {**feats, "hdr": levels[count]["hdr"]}
                _require_features(own_dir, name, count, feats, features)
                check = functools.partial(_check_own, alb=feats["alb"])
                n += _write_input(
                    dst / own_dir.name,
                    name,
                    ref,
                    levels[None]["hdr"],
                    feats["hdr"],
                    feats,
                    count,
                    "spp",
                    noisy_spp,
                    (),
                    features,
                    check,
                )
            if not ref_out.exists() or ref_out.stat().st_mtime < levels[None]["hdr"].stat().st_mtime:
                if not np.isfinite(ref.pixels).all():
                    raise contract.ContractError(f"{ref.path}: non-finite values")
                _save(ref_out, ref.pixels)
                n += 1
            shown.update()
    return n


def _require_features(where, name, count, feats, features):
    """ContractError unless an input set `feats` ({kind: path}) has every one of `features`."""
    missing = [f for f in features if f not in feats]
    if missing:
        raise contract.ContractError(
            f"{where}: {name} at {count} spp lacks {', '.join(missing)} (aov-write writes the "
            "features; re-render the dataset with make noisy reference)"
        )


def _realizations(src, scenes, extra_seeds):
    """{k: (`<src>/seed<k>`, its contract.scan)} of the extra noise realizations of seeds
    `extra_seeds` (make noisy's NOISY_EXTRA_SEEDS), each paired with its scene's reference among
    `scenes` (the split's scan); an error, before anything is written, for a missing directory or
    a realization of a scene the split has no reference for."""
    out = {}
    for k in sorted(set(extra_seeds)):
        sub = src / contract.REALIZATION_DIR.format(seed=k)
        if not sub.is_dir():
            raise contract.ContractError(
                f"{sub}: no such directory (the extra noise realization of seed {k}: make noisy renders it)"
            )
        out[k] = (sub, contract.scan(sub))
        for name in out[k][1]:
            if "hdr" not in scenes.get(name, {}).get(None, {}):
                raise contract.ContractError(f"{sub}: {name} has no reference image in {src}")
    return out


def _check_realization(noisy, seed, twin):
    """ContractError unless a realization's header seed is its directory's `seed` and differs from
    that of `twin` (the split's own image of the level, or None): the same samples twice."""
    found = noisy.value(contract.SEED, required=True)
    if found != seed:
        raise contract.ContractError(f"{noisy.path}: {contract.SEED} = {found} in a directory of seed {seed}")
    if twin is not None and contract.read(twin).value(contract.SEED) == seed:
        raise contract.ContractError(
            f"{noisy.path} and {twin}: the same {contract.SEED} = {seed} (a realization must have a seed of its own)"
        )


def _check_own(noisy, alb):
    """ContractError unless the own-sample features `alb` have the seed and the samples of the
    radiance image `noisy` they go with."""
    a = contract.read(alb)
    for key in (contract.SEED, contract.SAMPLES):
        if a.value(key, required=True) != noisy.value(key, required=True):
            raise contract.ContractError(
                f"{alb}: {key} = {a.value(key)}, its radiance {noisy.path} {noisy.value(key)} "
                "(the features of a level's own samples: aov-write --min-samples 1, the radiance's seed)"
            )


def _write_input(
    dst, name, ref, ref_path, hdr_path, feats, count_in_name, unit, noisy_spp, dle_paths, features, check=None
):
    """Writes one input array and its JSON unless unwanted or up to date; returns 1 if written.
    `check(noisy)` runs on the input before it is written."""
    if not dataset.wanted(unit, count_in_name, noisy_spp, dle_paths):
        return 0
    dst.mkdir(parents=True, exist_ok=True)
    out = dst / dataset.prep_name(name, count_in_name, unit)
    meta_out = out.with_suffix(".json")
    paths = [hdr_path] + [feats[f] for f in features[1:]]
    newest = max(p.stat().st_mtime for p in paths + [ref_path])
    if (
        meta_out.exists()
        and meta_out.stat().st_mtime >= newest
        and out.exists()
        and json.loads(meta_out.read_text()).get("channels") == list(features)
    ):
        return 0
    noisy = contract.read(hdr_path)
    if check:
        check(noisy)
    count = samples_of(noisy, count_in_name)
    check_pair(ref, noisy)
    if unit == "spp" and count > ref.value(contract.SAMPLES, required=True):
        raise contract.ContractError(
            f"{ref.path}: {ref.value(contract.SAMPLES)} samples per pixel, fewer than its input {hdr_path} "
            f"({count}); re-render the references (make reference)"
        )
    planes = [noisy.pixels] + [contract.read_rgb(p) for p in paths[1:]]
    for path, plane in zip(paths, planes):
        if plane.shape != ref.pixels.shape:
            raise contract.ContractError(
                f"{path}: {plane.shape[1]}x{plane.shape[0]} pixels, its reference {Path(ref.path).name} "
                f"{ref.pixels.shape[1]}x{ref.pixels.shape[0]}"
            )
    arr = np.concatenate(planes, axis=-1)
    if not np.isfinite(arr).all():
        raise contract.ContractError(f"{hdr_path}: non-finite values")
    meta = {
        "name": name,
        "samples": count,
        "unit": unit,
        "estimator": noisy.value(contract.ESTIMATOR),
        "seed": noisy.value(contract.SEED),
        "features": feats["alb"].name,
        "channels": list(features),
        "reference_seed": ref.value(contract.SEED),
        "reference_samples": ref.value(contract.SAMPLES),
        "exposures": dataset.whole_image_exposures(noisy.pixels),
    }
    _save(out, arr)
    tmp = meta_out.with_name(meta_out.name + ".tmp")
    tmp.write_text(json.dumps(meta, indent=1))
    tmp.replace(meta_out)
    return 1


def _save(out, arr):
    tmp = out.with_suffix(".tmp.npy")
    np.save(tmp, arr)
    tmp.replace(out)


SPLITS = ("train", "valid", "test")


def main(argv=None):
    cfg = config.parse(argv, __doc__.split("\n\n")[0])
    data = Path(cfg.data_dir)
    if not any(any((data / split).glob("*.exr")) for split in SPLITS if (data / split).is_dir()):
        sys.exit(
            f"preprocess: error: {data}: no images in train/, valid/ or test/ (make reference noisy renders a dataset)"
        )
    n = 0
    try:
        for split in SPLITS:
            # Extra noise realizations are training data (make noisy renders them for train only).
            n += preprocess_split(
                data / split,
                Path(cfg.prep_dir) / split,
                cfg.noisy_spp,
                cfg.dle_paths,
                cfg.features,
                cfg.extra_seeds if split == "train" else (),
                cfg.extra_spp,
                cfg.own_features,
            )
    except contract.ContractError as e:
        print(f"preprocess: error: {e}", file=sys.stderr)
        sys.exit(1)
    print(f"preprocess: {n} arrays written to {cfg.prep_dir}")


if __name__ == "__main__":
    main()
