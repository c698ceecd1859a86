"""The preprocessed dataset and its training crops.

preprocess.py turns each rendered image set (named as in luxest_contract: the OIDN training-
toolkit layout) into `<prep_dir>/<split>/<name>_<tag>.npy` — inputs (H, W, 9) hdr+alb+nrm per
noisy level (`tag` = `000004spp`) and per double-local-estimate image (`tag` = `001000le`, with
the features of the largest noisy level), references (H, W, 3) hdr (`tag` = `ref`) — and, per input, a
`<name>_<tag>.json` with what the headers and the whole image say: samples, seed (of the input
and of its reference) and the whole-image exposure under each of the six RGB channel orders
(`exposures`, in the order of `PERMUTATIONS`), so that a crop, even channel-shuffled, is
transferred with the exposure its whole image has at inference."""
import itertools
import json
from pathlib import Path

import numpy as np
import torch

import luxest_contract as contract

PERMUTATIONS = list(itertools.permutations(range(3)))
"""RGB channel orders, the index into a preprocessed input's `exposures`."""


def prep_name(name, spp, unit="spp"):
    """`<name>_<tag>.npy` of a preprocessed array (spp None: the reference; unit `le`: a
    double-local-estimate input at `spp` light paths)."""
    return f"{name}_{'ref' if spp is None else contract.count_tag(spp, unit)}.npy"


def whole_image_exposures(hdr):
    """contract.exposure of an (H, W, 3) image under each channel order of PERMUTATIONS."""
    return [contract.exposure(hdr[..., list(p)]) for p in PERMUTATIONS]


def wanted(unit, count, noisy_spp, dle_paths):
    """Whether an input of `unit` (`spp`: a noisy level, `le`: a local-estimate image) at `count`
    samples or light paths is among the configured ones (None: every one of that family)."""
    levels = noisy_spp if unit == "spp" else dle_paths
    return levels is None or count in levels


def pairs(prep_split_dir, noisy_spp=None, dle_paths=None):
    """[(input path, reference path, metadata dict)] of one preprocessed split: the noisy levels
    in `noisy_spp` and the local-estimate images in `dle_paths` (None: all of that family), so
    that arrays left by an earlier configuration are not trained on."""
    out = []
    d = Path(prep_split_dir)
    for meta_path in sorted(list(d.glob("*spp.json")) + list(d.glob("*le.json"))):
        meta = json.loads(meta_path.read_text())
        if not wanted(meta.get("unit", "spp"), meta["samples"], noisy_spp, dle_paths):
            continue
        out.append((meta_path.with_suffix(".npy"), d / prep_name(meta["name"], None), meta))
    return out


class Crops(torch.utils.data.Dataset):
    """Random training crops: (input 9 or 12 x H x W, reference 3xHxW, exposure) with flips,
    transposes and a random permutation of the RGB channels applied alike to hdr, albedo,
    emission and reference;
    the exposure is the stored whole-image exposure of the input under that permutation."""

    def __init__(self, prep_split_dir, crop, seed, length=100_000, noisy_spp=None, dle_paths=None):
        self.pairs = [(np.load(i, mmap_mode="r"), np.load(r, mmap_mode="r"), m["exposures"])
                      for i, r, m in pairs(prep_split_dir, noisy_spp, dle_paths)]
        if not self.pairs:
            raise FileNotFoundError(f"{prep_split_dir}: no preprocessed pairs (run preprocess.py)")
        self.crop, self.seed, self.length = crop, seed, length

    def __len__(self):
        return self.length

    def __getitem__(self, i):
        rng = np.random.default_rng((self.seed, i))
        inp, ref, exposures = self.pairs[rng.integers(len(self.pairs))]
        h, w = ref.shape[:2]
        c = self.crop
        y, x = rng.integers(0, h - c + 1), rng.integers(0, w - c + 1)
        a = np.array(inp[y:y + c, x:x + c], dtype=np.float32)
        b = np.array(ref[y:y + c, x:x + c], dtype=np.float32)
        if rng.random() < 0.5:
            a, b = a[:, ::-1], b[:, ::-1]
        if rng.random() < 0.5:
            a, b = a[::-1], b[::-1]
        if rng.random() < 0.5:
            a, b = a.transpose(1, 0, 2), b.transpose(1, 0, 2)
        k = int(rng.integers(len(PERMUTATIONS)))
        perm = np.array(PERMUTATIONS[k])
        # hdr, alb, emi and ema are colours (permuted alike); nrm (the third feature) is a direction.
        a = np.concatenate([a[..., 6:9] if i == 2 else a[..., 3 * i + perm] for i in range(a.shape[-1] // 3)], axis=-1)
        b = b[..., perm]
        to = lambda t: torch.from_numpy(np.ascontiguousarray(t.transpose(2, 0, 1)))
        return to(a), to(b), torch.tensor(exposures[k], dtype=torch.float32)
