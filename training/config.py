"""All options of the training toolkit in one place (as in OIDN's toolkit); every run saves
its config next to its checkpoints."""
import argparse
import json
from dataclasses import asdict, dataclass, field

import luxest_contract as contract


NETWORK = ("base_width", "head", "features", "detail_gate", "scales")
"""The options that fix the network's shape (model.denoiser): a run resumes, and a committed
model's record matches its metadata, only when these agree."""


@dataclass
class Config:
    data_dir: str = "data/quick"        # data/<dataset> with train/ valid/ test/
    prep_dir: str = "build/train/quick"  # preprocessed .npy arrays
    run_dir: str = "runs/quick"          # checkpoints, config.json, log
    features: list = field(default_factory=lambda: list(contract.FEATURES))  # model.FEATURE_SETS
    noisy_spp: list = field(default_factory=lambda: [1, 2, 4, 8, 16, 32, 64, 256, 1024])
    dle_paths: list = field(default_factory=lambda: [100, 300, 1000])  # local-estimate inputs
    extra_seeds: list = field(default_factory=list)  # seeds of the extra noise realizations (<split>/seed<k>/) to use
    extra_spp: list = field(default_factory=lambda: [1, 2, 4, 8, 16, 32])  # their levels (make's NOISY_EXTRA_LEVELS)
    crop: int = 64                       # training crop side (multiple of 16)
    batch: int = 16
    base_width: int = 24                 # U-Net channels of the first level
    head: str = "kpn"                    # output: kpn (kernel-predicting) or direct (model.py)
    scales: int = 4                      # kpn: filtering scales, 4 (1 to 1/8: the decoder levels) or 5 (and 1/16: the bottleneck)
    detail_gate: bool = True             # kpn: each finer scale predicts how much of its detail to keep (model.py; --no-detail-gate)
    lr: float = 2e-3                     # peak learning rate of the one-cycle schedule
    minutes: float = 18.0                # training time budget
    steps: int = 3000                    # schedule length (stops earlier if out of time)
    schedule: str = "steps"              # the one cycle spans `steps` (steps) or `minutes` (time; steps a cap)
    ms_ssim_weight: float = 0.2          # loss = (1 - w) L1 + w (1 - MS-SSIM)
    loss: str = "l1"                     # l1: the line above; psnr: minus the evaluation's PSNR per crop (loss.py)
    seed: int = 1
    threads: int = 2
    workers: int = -1                    # DataLoader worker processes (-1: none on CPU, 8 on a GPU)
    cropper: str = "auto"                # where crops are cut: loader (DataLoader), device (the split in GPU memory), auto
    precision: str = "auto"              # autocast: bf16 | fp32 | auto (train.autocast_dtype)
    resume: bool = False
    init_from: str = ""                  # start from this model's weights (an exported .onnx or a run's checkpoint.pt); a new schedule

    def save(self, path):
        with open(path, "w") as f:
            json.dump(asdict(self), f, indent=2)

    @staticmethod
    def load(path):
        with open(path) as f:
            return Config.from_values(json.load(f))

    @staticmethod
    def from_values(values):
        """A Config from saved values (a run's config.json, a model's metadata `luxest.config`):
        keys missing from older saves get the value those runs had (head direct, dle_paths [],
        detail_gate false, ...); unknown keys are dropped."""
        values = {k: v for k, v in values.items() if k in Config.__dataclass_fields__}
        # Runs from before the `head` option predicted the radiance directly.
        values.setdefault("head", "direct")
        values.setdefault("dle_paths", [])
        values.setdefault("precision", "auto")
        values.setdefault("schedule", "steps")
        values.setdefault("cropper", "auto")
        values.setdefault("detail_gate", False)
        values.setdefault("loss", "l1")
        values.setdefault("scales", 4)
        return Config(**values)


def parse(argv=None, description=""):
    """Config from command-line flags (--data-dir, --minutes, ...)."""
    ap = argparse.ArgumentParser(description=description)
    defaults = Config()
    for k, v in asdict(defaults).items():
        flag = "--" + k.replace("_", "-")
        if isinstance(v, bool):
            ap.add_argument(flag, action=argparse.BooleanOptionalAction, default=v)
        elif isinstance(v, list):
            ap.add_argument(flag, type=type(v[0]) if v else int, nargs="*", default=v)
        else:
            ap.add_argument(flag, type=type(v), default=v)
    return Config(**vars(ap.parse_args(argv)))
