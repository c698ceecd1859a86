"""The preprocessed dataset and its training crops.

preprocess.py turns each rendered image set (named as in luxest_contract: the OIDN training-
toolkit layout) into `<prep_dir>/<split>/<name>_<tag>.npy` — inputs (H, W, 9) hdr+alb+nrm per
noisy level (`tag` = `000004spp`) and per double-local-estimate image (`tag` = `001000le`, with
the features of the largest noisy level), references (H, W, 3) hdr (`tag` = `ref`) — and, per input, a
`<name>_<tag>.json` with what the headers and the whole image say: samples, seed (of the input
and of its reference) and the whole-image exposure under each of the six RGB channel orders
(`exposures`, in the order of `PERMUTATIONS`), so that a crop, even channel-shuffled, is
transferred with the exposure its whole image has at inference. Extra noise realizations of a
split's noisy levels (`<split>/seed<k>/`, make noisy's NOISY_EXTRA_SEEDS) are preprocessed into
`<prep_dir>/<split>/seed<k>/` beside them and share their scene's reference."""

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


def whole_image_exposures(hdr, evaluation=False):
    """contract.exposure of an (H, W, 3) image under each channel order of PERMUTATIONS (the
    model's input transfer), or with `evaluation` contract.evaluation_exposure (a reference's, for
    the evaluation tonemap of --loss psnr)."""
    f = contract.evaluation_exposure if evaluation else contract.exposure
    return [f(hdr[..., list(p)]) for p in PERMUTATIONS]


def wanted(unit, count, noisy_spp, dle_paths):
    """Whether an input of `unit` (`spp`: a noisy level, `le`: a local-estimate image) at `count`
    samples or light paths is among the configured ones (None: every one of that family)."""
    levels = noisy_spp if unit == "spp" else dle_paths
    return levels is None or count in levels


def pairs(prep_split_dir, noisy_spp=None, dle_paths=None, extra_seeds=(), extra_spp=None, own_features=False):
    """[(input path, reference path, metadata dict)] of one preprocessed split: the noisy levels
    in `noisy_spp` and the local-estimate images in `dle_paths` (None: all of that family), so
    that arrays left by an earlier configuration are not trained on, then the noisy levels of
    the extra noise realizations of seeds `extra_seeds` (`seed<k>/`, paired with the split's
    references) at the levels in `extra_spp` (None: all), then with `own_features` the noisy
    levels with the features of their own sample count (`own/`, preprocess.py)."""
    out = []
    d = Path(prep_split_dir)
    realizations = [d / contract.REALIZATION_DIR.format(seed=k) for k in sorted(set(extra_seeds))]
    own = d / contract.OWN_FEATURES_DIR
    for meta_path in (
        sorted(list(d.glob("*spp.json")) + list(d.glob("*le.json")))
        + [m for r in realizations for m in sorted(r.glob("*spp.json"))]
        + (sorted(own.glob("*spp.json")) if own_features else [])
    ):
        meta = json.loads(meta_path.read_text())
        if not wanted(meta.get("unit", "spp"), meta["samples"], noisy_spp, dle_paths):
            continue
        if meta_path.parent in realizations and extra_spp is not None and meta["samples"] not in extra_spp:
            continue
        out.append((meta_path.with_suffix(".npy"), d / prep_name(meta["name"], None), meta))
    return out


def radiance_channels(channels):
    """The indices of the input channels that are radiance (hdr, emi, ema: scaled together by
    the input's power of two) among the features `channels`."""
    return [3 * g + j for g, name in enumerate(channels) if name in contract.RADIANCE_FEATURES for j in range(3)]


def input_scale(inp, channels, low):
    """The power of two 2**e by which a denoiser scales the radiance of input array `inp` (H, W,
    3 x features `channels`) for a model of MEAN_LUMINANCE `low` (contract.range_exponent of its
    hdr and emi; 1.0 when `low` is None, as training did before the key: its images were not dim)."""
    if low is None:
        return 1.0
    hdr = np.asarray(inp[..., :3], dtype=np.float32)
    emi = np.asarray(inp[..., 3 * channels.index("emi") : 3 * channels.index("emi") + 3]) if "emi" in channels else None
    return 2.0 ** contract.range_exponent(hdr, emi, low)


def groups(metas):
    """The pair indices grouped by what they are an image of — (scene, unit, count) — in the
    order of first appearance: a scene's noisy level, its extra noise realizations
    (`seed<k>/`) and its input with the features of its own samples (`own/`, preprocess.py)
    form one group."""
    out = {}
    for i, m in enumerate(metas):
        out.setdefault((m["name"], m.get("unit", "spp"), m["samples"]), []).append(i)
    return list(out.values())


class Crops(torch.utils.data.Dataset):
    """Random training crops: (input 9 or 12 x H x W, reference 3xHxW, exposure, reference
    exposure) with flips, transposes and a random permutation of the RGB channels applied alike
    to hdr, albedo, emission and reference; the exposure is the stored whole-image exposure of
    the input under that permutation (the network's transfer), the reference exposure that of
    the whole reference (the evaluation's tonemap, loss.display)."""

    def __init__(
        self,
        prep_split_dir,
        crop,
        seed,
        length=100_000,
        noisy_spp=None,
        dle_paths=None,
        extra_seeds=(),
        extra_spp=None,
        start=0,
        own_features=False,
        mean_luminance=None,
    ):
        refs = {}  # a scene's inputs share its reference array (DeviceCrops holds it once)
        ref_exposures_at = {}  # (reference, scale): its exposures
        self.pairs, self.scales, self.radiance = [], [], None
        found = pairs(prep_split_dir, noisy_spp, dle_paths, extra_seeds, extra_spp, own_features)
        self.groups = groups([m for *_, m in found])
        for i, r, m in found:
            if r not in refs:
                refs[r] = np.load(r, mmap_mode="r")
            ref, inp = refs[r], np.load(i, mmap_mode="r")
            # With MEAN_LUMINANCE the input and its reference are scaled by the power of two a
            # denoiser applies (input_scale): the crop gets the exposures of the scaled images.
            s = input_scale(inp, m["channels"], mean_luminance)
            if (r, s) not in ref_exposures_at:
                ref_exposures_at[(r, s)] = whole_image_exposures(np.asarray(ref, dtype=np.float64) * s, evaluation=True)
            exposures = (
                m["exposures"]
                if s == 1.0
                else [contract.exposure(np.asarray(inp[..., list(p)], dtype=np.float32), s) for p in PERMUTATIONS]
            )
            self.pairs.append((inp, ref, exposures, ref_exposures_at[(r, s)]))
            self.scales.append(s)
            self.radiance = radiance_channels(m["channels"])
        if not self.pairs:
            raise FileNotFoundError(f"{prep_split_dir}: no preprocessed pairs (run preprocess.py)")
        self.split_dir, self.crop, self.seed, self.length = Path(prep_split_dir), crop, seed, length
        # Crop i of this dataset is crop start + i of the seed's sequence: a run resumed at step s
        # takes the crops an uninterrupted run takes from step s on.
        self.start = start

    def __len__(self):
        return self.length

    def draw(self, i):
        """The random choices of crop i, from (seed, start + i) alone: (pair index, top, left, flip the
        columns, flip the rows, transpose, index into PERMUTATIONS). The pair is drawn as a group
        (a scene's image at one count, `groups`), then one of its noise realizations, so that
        extra realizations add variety to their levels without weighting them more."""
        rng = np.random.default_rng((self.seed, self.start + i))
        g = self.groups[int(rng.integers(len(self.groups)))]
        p = g[0] if len(g) == 1 else g[int(rng.integers(len(g)))]
        h, w = self.pairs[p][1].shape[:2]
        c = self.crop
        y, x = int(rng.integers(0, h - c + 1)), int(rng.integers(0, w - c + 1))
        flip_x, flip_y, swap = (bool(rng.random() < 0.5) for _ in range(3))
        return p, y, x, flip_x, flip_y, swap, int(rng.integers(len(PERMUTATIONS)))

    def __getitem__(self, i):
        p, y, x, flip_x, flip_y, swap, k = self.draw(i)
        inp, ref, exposures, ref_exposures = self.pairs[p]
        c = self.crop
        a = np.array(inp[y : y + c, x : x + c], dtype=np.float32)
        b = np.array(ref[y : y + c, x : x + c], dtype=np.float32)
        s = self.scales[p]
        if s != 1.0:  # a power of two: exact in float32
            a[..., self.radiance] *= np.float32(s)
            b *= np.float32(s)
        if flip_x:
            a, b = a[:, ::-1], b[:, ::-1]
        if flip_y:
            a, b = a[::-1], b[::-1]
        if swap:
            a, b = a.transpose(1, 0, 2), b.transpose(1, 0, 2)
        order = channel_order(k, a.shape[-1])
        a, b = a[..., order], b[..., order[:3]]
        to = lambda t: torch.from_numpy(np.ascontiguousarray(t.transpose(2, 0, 1)))
        return (
            to(a),
            to(b),
            torch.tensor(exposures[k], dtype=torch.float32),
            torch.tensor(ref_exposures[k], dtype=torch.float32),
        )


def channel_order(k, channels):
    """The input channels in the order of RGB permutation `k` (PERMUTATIONS): hdr, alb, emi and
    ema are colours, permuted alike; nrm (the third feature) is a direction, kept. Its first three
    entries permute a reference."""
    perm = PERMUTATIONS[k]
    return [3 * g + (j if g == 2 else perm[j]) for g in range(channels // 3) for j in range(3)]


class DeviceCrops:
    """The crops of a `Crops` cut on `device` (a GPU) from the whole split held in its memory,
    a batch in one gather: crop i is exactly `crops[i]`, without worker processes, which on a GPU
    cut crops more slowly than it trains on them. A batch's (N, C, H, W) tensors are views of
    (N, H, W, C) ones: channels_last already."""

    @staticmethod
    def bytes_held(crops):
        """The bytes of device memory the arrays of `crops` (a `Crops`) take in a DeviceCrops:
        every input and each scene's reference once, float32 (the host holds one array at a time
        while they are copied)."""
        refs = {id(ref): ref.size for _, ref, *_ in crops.pairs}
        return 4 * (sum(inp.size for inp, *_ in crops.pairs) + sum(refs.values()))

    def __init__(self, crops, device):
        self.crops, self.device = crops, torch.device(device)
        channels = {pair[0].shape[-1] for pair in crops.pairs}
        if len(channels) != 1:
            raise ValueError(f"inputs of {sorted(channels)} channels in one split")
        starts, ref_starts, widths, refs, n, m = [], [], [], {}, 0, 0
        for inp, ref, *_ in crops.pairs:  # where each array goes in the two flat tensors
            if id(ref) not in refs:
                refs[id(ref)] = (m, ref)
                m += ref.shape[0] * ref.shape[1]
            starts.append(n)
            ref_starts.append(refs[id(ref)][0])
            widths.append(inp.shape[1])
            n += inp.shape[0] * inp.shape[1]
        # Allocated once on the device and filled array by array: the host holds one copy at a time.
        self.inputs = torch.empty((n, channels.pop()), dtype=torch.float32, device=self.device)
        self.refs = torch.empty((m, 3), dtype=torch.float32, device=self.device)
        fill = lambda dst, at, arr: dst[at : at + arr.shape[0] * arr.shape[1]].copy_(
            torch.from_numpy(np.array(arr, dtype=np.float32)).reshape(-1, arr.shape[-1])
        )
        for (inp, *_), at in zip(crops.pairs, starts):
            fill(self.inputs, at, inp)
        for at, ref in refs.values():
            fill(self.refs, at, ref)
        to = lambda t: t.to(self.device)
        long = lambda v: to(torch.tensor(v, dtype=torch.int64))
        self.starts, self.ref_starts, self.widths = long(starts), long(ref_starts), long(widths)
        self.orders = long([channel_order(k, self.inputs.shape[1]) for k in range(len(PERMUTATIONS))])
        self.exposures = to(torch.tensor([e for _, _, e, _ in crops.pairs], dtype=torch.float32))
        self.ref_exposures = to(torch.tensor([e for *_, e in crops.pairs], dtype=torch.float32))
        # Each pair's power of two (Crops.scales) on its radiance channels and reference.
        self.scales = to(torch.tensor(crops.scales, dtype=torch.float32))
        mask = torch.zeros(self.inputs.shape[1], dtype=torch.bool)
        mask[crops.radiance] = True
        self.radiance = to(mask)
        grid = torch.arange(crops.crop, device=self.device)
        self.rows, self.cols = grid.view(1, -1, 1), grid.view(1, 1, -1)

    def batch(self, indices):
        """(inputs, references, exposures, reference exposures) of crops `indices`, as a
        DataLoader batches them."""
        draws = torch.tensor([self.crops.draw(i) for i in indices], dtype=torch.int64)
        if self.device.type == "cuda":  # one asynchronous copy (a pageable one waits for the GPU)
            draws = draws.pin_memory().to(self.device, non_blocking=True)
        else:
            draws = draws.to(self.device)
        p, y, x, flip_x, flip_y, swap, k = (c.view(-1, 1, 1) for c in draws.unbind(1))
        flip_x, flip_y, swap = flip_x.bool(), flip_y.bool(), swap.bool()
        last = self.crops.crop - 1
        r = torch.where(swap, self.cols, self.rows)  # output pixel (u, v) reads (v, u) when swapped
        s = torch.where(swap, self.rows, self.cols)
        r = torch.where(flip_y, last - r, r) + y
        s = torch.where(flip_x, last - s, s) + x
        pixel = r * self.widths[p] + s
        a = self.inputs[self.starts[p] + pixel]  # (N, c, c, C)
        b = self.refs[self.ref_starts[p] + pixel]
        order = self.orders[k.view(-1)][:, None, None, :]
        scale = self.scales[p.view(-1)].view(-1, 1, 1, 1)
        a = a * torch.where(self.radiance, scale, torch.ones_like(scale))
        b = b * scale
        a = torch.gather(a, 3, order.expand_as(a))
        b = torch.gather(b, 3, order[..., :3].expand_as(b))
        at = (p.view(-1), k.view(-1))
        return a.permute(0, 3, 1, 2), b.permute(0, 3, 1, 2), self.exposures[at], self.ref_exposures[at]
