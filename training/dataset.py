"""The OIDN training-toolkit naming: `<name>_<spp, digits>spp.<feature>.exr` and
`<name>_ref.<feature>.exr`, features hdr, alb, nrm. Preprocessed arrays live in
`<prep_dir>/<split>/<name>_<tag>.npy` with the 9 channels hdr+alb+nrm (H, W, 9) for inputs and
hdr (H, W, 3) for references."""
import re
from pathlib import Path

import numpy as np
import torch

NAME = re.compile(r"^(?P<name>.+)_(?:(?P<spp>\d+)spp|ref)\.(?P<feature>[a-z]+)\.exr$")


def parse_name(filename):
    """(name, spp or None for the reference, feature), or None if it is not a dataset file."""
    m = NAME.match(filename)
    if not m:
        return None
    spp = m.group("spp")
    return m.group("name"), (int(spp) if spp is not None else None), m.group("feature")


def scan(split_dir):
    """{name: {spp or None: {feature: path}}} for one split directory."""
    out = {}
    for p in sorted(Path(split_dir).glob("*.exr")):
        parsed = parse_name(p.name)
        if parsed:
            name, spp, feature = parsed
            out.setdefault(name, {}).setdefault(spp, {})[feature] = p
    return out


class Crops(torch.utils.data.Dataset):
    """Random training crops: (input 9xHxW, reference 3xHxW) with flips, transposes and a
    random permutation of the RGB channels applied alike to hdr, albedo and reference."""

    def __init__(self, prep_split_dir, crop, seed, length=100_000):
        self.pairs = []
        d = Path(prep_split_dir)
        for ref in sorted(d.glob("*_ref.npy")):
            name = ref.name[: -len("_ref.npy")]
            target = np.load(ref, mmap_mode="r")
            for inp in sorted(d.glob(f"{name}_*spp.npy")):
                self.pairs.append((np.load(inp, mmap_mode="r"), target))
        if not self.pairs:
            raise FileNotFoundError(f"{prep_split_dir}: no preprocessed pairs (run preprocess.py)")
        self.crop, self.seed, self.length = crop, seed, length

    def __len__(self):
        return self.length

    def __getitem__(self, i):
        rng = np.random.default_rng((self.seed, i))
        inp, ref = self.pairs[rng.integers(len(self.pairs))]
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
        perm = rng.permutation(3)
        a = np.concatenate([a[..., perm], a[..., 3 + perm], a[..., 6:9]], axis=-1)
        b = b[..., perm]
        to = lambda t: torch.from_numpy(np.ascontiguousarray(t.transpose(2, 0, 1)))
        return to(a), to(b)
