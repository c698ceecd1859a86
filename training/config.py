"""All options of the training toolkit in one place (as in OIDN's toolkit); every run saves
its config next to its checkpoints. The options that are preset values (the noisy levels, the
local-estimate light paths, the extra noise realizations, the training steps, minutes, schedule
and loss) default to pipelines/presets.mk's, read from that file, so that `python train.py` trains
as `make train` does."""

import argparse
import functools
import json
import os
import re
from dataclasses import asdict, dataclass, field
from pathlib import Path

import luxest_contract as contract

PRESETS_MK = Path(__file__).resolve().parent.parent / "pipelines" / "presets.mk"
"""The one home of the preset values (make includes it)."""

_PRESET_LINE = re.compile(r"^\$\(eval \$\(call lx_preset,(\w+),([^,]*),([^,]*)\)\)$")
_ASSIGNMENT = re.compile(r"^(\w+)\s*(\?=|:=)\s*(.*?)\s*$")


def presets(preset=None, path=PRESETS_MK, environ=None):
    """{NAME: value text} of presets.mk's variables as make reads them for `preset` (quick or full;
    None: the PRESET environment variable, else presets.mk's own default): its
    `$(eval $(call lx_preset,NAME,QUICK,FULL))` lines and plain `NAME ?= value` and `NAME := value`
    lines. As in make, an environment variable replaces a `?=` value (the presets are `?=` too)."""
    environ = os.environ if environ is None else environ
    lines = Path(path).read_text().splitlines()
    values = {}
    for line in lines:
        m = _ASSIGNMENT.match(line)
        if m:
            name, op, value = m.groups()
            values[name] = environ.get(name, value) if op == "?=" else value
    preset = preset or values.get("PRESET")
    if preset not in ("quick", "full"):
        raise SystemExit(f"config: PRESET={preset}: expected quick or full ({path})")
    values["PRESET"] = preset
    for line in lines:
        m = _PRESET_LINE.match(line)
        if m:
            name, quick, full = m.groups()
            values[name] = environ.get(name, full if preset == "full" else quick)
    return values


@functools.cache
def _presets():
    return presets()


def preset_text(name):
    """The value of presets.mk's variable `name` for this process's preset (`presets`)."""
    return _presets()[name]


def preset_ints(name):
    """A list-valued preset (`NOISY_LEVELS`: "1 2 4 ...") as integers."""
    return [int(v) for v in preset_text(name).split()]


def feature_samples(cfg):
    """The least samples per pixel of albedo and normal a model trained with `cfg` takes (its
    metadata FEATURE_SAMPLES): 1 when it was trained on the features of each level's own samples
    too, else FEATURE_SPP."""
    return 1 if cfg.own_features else int(preset_text("FEATURE_SPP"))


def scale_luminance(cfg):
    """The model's MEAN_LUMINANCE of `cfg` (None: unscaled)."""
    return cfg.mean_luminance if cfg.mean_luminance > 0 else None


def preset_extra_spp():
    """The levels of the extra noise realizations as make passes them: those of
    NOISY_EXTRA_LEVELS among NOISY_LEVELS, in NOISY_LEVELS' order (pipelines/dataset.mk's
    NOISY_EXTRA)."""
    extra = set(preset_ints("NOISY_EXTRA_LEVELS"))
    return [n for n in preset_ints("NOISY_LEVELS") if n in extra]


NETWORK = ("base_width", "head", "features", "detail_gate", "scales")
"""The options that fix the network's shape (model.denoiser): a run resumes, and a committed
model's record matches its metadata, only when these agree."""


@dataclass
class Config:
    # Paths: data/<dataset> with train/ valid/ test/; preprocessed .npy arrays; checkpoints,
    # config.json and log.
    data_dir: str = field(default_factory=lambda: f"data/{preset_text('PRESET')}")
    prep_dir: str = field(default_factory=lambda: f"build/train/{preset_text('PRESET')}")
    run_dir: str = field(default_factory=lambda: f"runs/{preset_text('PRESET')}")
    features: list = field(default_factory=lambda: list(contract.FEATURES))  # model.FEATURE_SETS
    noisy_spp: list = field(default_factory=lambda: preset_ints("NOISY_LEVELS"))
    dle_paths: list = field(default_factory=lambda: preset_ints("DATASET_DLE"))  # local-estimate inputs
    # The extra noise realizations (<split>/seed<k>/) to use, and their levels.
    extra_seeds: list = field(default_factory=lambda: preset_ints("NOISY_EXTRA_SEEDS"))
    extra_spp: list = field(default_factory=preset_extra_spp)
    # Also train on the noisy levels with the features of their own sample count (<split>/own/):
    # one of the two feature sets per crop. The model then takes either (FEATURE_SAMPLES 1);
    # without, the antialiased ones only (FEATURE_SPP, pipelines/presets.mk).
    own_features: bool = True
    # The mean luminance [v, 2 v) the input radiance is scaled into by a power of two, dim or
    # bright (luxest_contract.range_exponent; the model's MEAN_LUMINANCE); 0: unscaled, only dim
    # images brightened at inference (models trained before the option).
    mean_luminance: float = 0.0625
    crop: int = 64  # training crop side (multiple of 16)
    batch: int = 16
    base_width: int = 24  # U-Net channels of the first level
    head: str = "kpn"  # output: kpn (kernel-predicting) or direct (model.py)
    scales: int = 4  # kpn: filtering scales, 4 (1 to 1/8: the decoder levels) or 5 (and 1/16: the bottleneck)
    # kpn: each finer scale predicts how much of its detail to keep (model.py; --no-detail-gate).
    detail_gate: bool = True
    lr: float = 2e-3  # peak learning rate of the one-cycle schedule
    minutes: float = field(default_factory=lambda: float(preset_text("TRAIN_MINUTES")))  # training time budget
    steps: int = field(default_factory=lambda: int(preset_text("TRAIN_STEPS")))  # schedule length (or cap)
    # The one cycle spans `steps` (steps) or `minutes` (time; steps a cap).
    schedule: str = field(default_factory=lambda: preset_text("TRAIN_SCHEDULE"))
    ms_ssim_weight: float = 0.2  # loss = (1 - w) L1 + w (1 - MS-SSIM)
    # l1: the line above; psnr: minus the evaluation's PSNR per crop (loss.py).
    loss: str = field(default_factory=lambda: preset_text("TRAIN_LOSS"))
    seed: int = 1
    threads: int = 2
    workers: int = -1  # DataLoader worker processes (-1: none on CPU, 8 on a GPU)
    cropper: str = "auto"  # where crops are cut: loader (DataLoader), device (the split in GPU memory), auto
    precision: str = "auto"  # autocast: bf16 | fp32 | auto (train.autocast_dtype)
    resume: bool = False
    # Steps between checkpoints: a killed, pre-empted or requeued run (--resume) goes on from the
    # last; with `--schedule steps` it then ends as the uninterrupted run would.
    checkpoint_every: int = 200
    init_from: str = ""  # start from this model's weights (an exported .onnx or a run's checkpoint.pt); a new schedule

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
        values.setdefault("own_features", False)
        values.setdefault("mean_luminance", 0.0)
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
