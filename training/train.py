#!/usr/bin/env python3
"""Trains the denoiser: Adam with a one-cycle schedule on random crops, L1 + MS-SSIM in the
transferred domain (each crop with its whole image's exposure, stored by preprocess.py) or
minus the evaluation's PSNR (--loss psnr, loss.py),
checkpoints and the run's config in <run_dir>, resumable (--resume), channels_last, bf16
autocast where it pays (--precision). Stops at the step count or the time budget; with
`--schedule time` the one cycle spans the time budget (all resumed runs together), so that a
run on a machine of unknown speed anneals when its time is up."""

import json
import math
import os
import sys
import time
from dataclasses import asdict
from pathlib import Path

import torch

import config
import dataset
import grow
import luxest_contract as contract
import loss as losses
import model
import progress
import transfer


def autocast_dtype(device, precision, cpu_capability=None):
    """The autocast dtype of the forward pass: torch.bfloat16 or None (float32).

    `auto` takes bf16 on CUDA and on CPUs whose PyTorch kernels use AVX-512 (oneDNN's bf16
    paths), float32 elsewhere: on an AVX2-only CPU PyTorch emulates bf16, and a training step
    took 2.2 s instead of 0.28 s in float32 (AMD EPYC, 2 threads)."""
    if precision not in ("auto", "bf16", "fp32"):
        raise SystemExit(f"train: --precision {precision!r}: expected auto, bf16 or fp32")
    if precision == "auto":
        if device.type == "cpu":
            capability = cpu_capability or torch.backends.cpu.get_cpu_capability()
            precision = "bf16" if capability.startswith("AVX512") or "AMX" in capability else "fp32"
        else:
            precision = "bf16"
    return torch.bfloat16 if precision == "bf16" else None


class TimeOneCycle:
    """The one-cycle schedule of torch's OneCycleLR (pct_start 0.15, cosine phases, Adam's beta1
    cycled 0.95 -> 0.85 -> 0.95, start max_lr / 25, end that / 1e4) as a function of the
    progress max(step / steps, seconds / budget): the cycle ends at whichever limit comes
    first. Stateless: a resumed run recomputes the rates from its step and its seconds."""

    PCT, DIV, FINAL_DIV, BETA_LOW, BETA_HIGH = 0.15, 25.0, 1e4, 0.85, 0.95

    def __init__(self, opt, max_lr, steps, seconds):
        self.opt, self.max_lr, self.steps, self.seconds = opt, max_lr, steps, seconds
        self.last = self.rates(0.0)
        self.apply(*self.last)

    def rates(self, progress):
        """(learning rate, beta1) at `progress` in [0, 1]."""
        start = self.max_lr / self.DIV
        end = start / self.FINAL_DIV
        cos = lambda a, b, t: b + (a - b) / 2.0 * (1.0 + math.cos(math.pi * t))  # a at t = 0, b at 1
        p = min(max(progress, 0.0), 1.0)
        if p <= self.PCT:
            t = p / self.PCT
            return cos(start, self.max_lr, t), cos(self.BETA_HIGH, self.BETA_LOW, t)
        t = (p - self.PCT) / (1.0 - self.PCT)
        return cos(self.max_lr, end, t), cos(self.BETA_LOW, self.BETA_HIGH, t)

    def progress(self, step, seconds):
        return max(step / max(self.steps, 1), seconds / self.seconds if self.seconds > 0 else 1.0)

    def apply(self, lr, beta1):
        for g in self.opt.param_groups:
            g["lr"] = lr
            g["betas"] = (beta1, g["betas"][1])

    def at(self, step, seconds):
        """Sets the rates of the step about to be taken after `step` steps and `seconds`."""
        self.last = self.rates(self.progress(step, seconds))
        self.apply(*self.last)

    def done(self, step, seconds):
        return self.progress(step, seconds) >= 1.0

    def get_last_lr(self):
        return [self.last[0]]

    def state_dict(self):
        return {}

    def load_state_dict(self, state):
        pass


def loader_workers(workers, device):
    """DataLoader worker processes: `workers`, or where it is -1 none on a CPU (the crops cost
    little next to a CPU training step, and the 2 threads train) and 8 on a GPU, whose steps
    are faster than one process cuts crops."""
    if workers < -1:
        raise SystemExit(f"train: --workers {workers}: expected -1 (automatic) or a count >= 0")
    return workers if workers >= 0 else (0 if device.type == "cpu" else 8)


# Of the device memory free when the crops are set up (the network already there), the share
# the split's arrays may take in DeviceCrops; the rest is for Adam's moments, a batch's
# activations and the convolutions' workspace.
DEVICE_SHARE = 0.75


def free_memory(device):
    """Bytes of memory free on `device` now: a GPU's free memory, the host's MemAvailable for
    the CPU; None where unknown."""
    if device.type == "cuda":
        torch.cuda.empty_cache()  # memory PyTorch keeps cached but unused counts as free
        return torch.cuda.mem_get_info(device)[0]
    if device.type == "cpu":
        try:
            with open("/proc/meminfo") as f:
                return next((int(line.split()[1]) * 1024 for line in f if line.startswith("MemAvailable:")), None)
        except OSError:
            return None
    return None


def cropper(choice, device, need=0, free=None, split="the split"):
    """Where crops are cut: `device` (the whole split in the training device's memory, a batch in
    one gather: dataset.DeviceCrops) or `loader` (a DataLoader, worker processes per
    loader_workers); `auto` takes device on a GPU, where worker processes cut crops more slowly
    than it trains, and loader on a CPU. Both cut the same crops. The split's arrays (`need`
    bytes) must fit in DEVICE_SHARE of the device's `free` bytes (None: not checked): where they
    do not, `auto` takes loader (saying so on stderr) and `device` refuses."""
    if choice not in ("auto", "device", "loader"):
        raise SystemExit(f"train: --cropper {choice!r}: expected auto, device or loader")
    where = ("loader" if device.type == "cpu" else "device") if choice == "auto" else choice
    if where == "device" and free is not None and need > DEVICE_SHARE * free:
        why = (
            f"{split}: its arrays take {need / 2**30:.2f} GiB, more than {DEVICE_SHARE:.0%} of the "
            f"{free / 2**30:.2f} GiB free on {device}"
        )
        if choice == "device":
            raise SystemExit(f"train: --cropper device: {why} (--cropper loader cuts crops from the files)")
        print(f"train: {why}: crops are cut by a DataLoader instead", file=sys.stderr)
        return "loader"
    return where


def batches(data, cfg, device):
    """The training batches of `data` (dataset.Crops), cut where `cropper` says."""
    where = cropper(cfg.cropper, device)
    if where == "device":  # then the split's arrays must fit the device's memory
        where = cropper(cfg.cropper, device, dataset.DeviceCrops.bytes_held(data), free_memory(device), data.split_dir)
    if where == "device":
        cut = dataset.DeviceCrops(data, device)
        return (cut.batch(range(j, min(j + cfg.batch, len(data)))) for j in range(0, len(data), cfg.batch))
    return iter(
        torch.utils.data.DataLoader(
            data,
            batch_size=cfg.batch,
            num_workers=loader_workers(cfg.workers, device),
            pin_memory=device.type == "cuda",
        )
    )


LOSSES = ("l1", "psnr")


def objective(net, out, exp, ref, ref_exp, cfg):
    """The training loss of the network's output `out` (net.transferred, exposures `exp`)
    against linear reference radiance `ref` whose whole images have exposures `ref_exp`:
    `l1`, L1 + MS-SSIM in the transferred domain, or `psnr`, minus the evaluation's PSNR per crop
    (loss.py)."""
    if cfg.loss == "psnr":
        return losses.psnr_loss(net.linear(out.float(), exp.float()), ref.float(), ref_exp.float())
    return losses.loss(net.loss_domain(out.float(), exp), transfer.forward(ref, exp.float()), cfg.ms_ssim_weight)


def validation_loss(net, prep_dir, cfg):
    """Mean loss on centre crops of the valid split (all noisy levels, with both feature sets
    where the run trains on both), each transferred with its whole image's exposure, scaled as
    the model scales it (dataset.input_scale)."""
    import numpy as np

    total, n = 0.0, 0
    to = lambda arr: torch.from_numpy(arr.transpose(2, 0, 1).copy())[None]
    ref_exposures = {}  # of each whole reference at each scale, once
    low = config.scale_luminance(cfg)
    with torch.no_grad():
        for inp_path, ref_path, meta in dataset.pairs(
            Path(prep_dir) / "valid", cfg.noisy_spp, cfg.dle_paths, own_features=cfg.own_features
        ):
            inp = np.load(inp_path)
            s = dataset.input_scale(inp, meta["channels"], low)
            ref = np.load(ref_path) * np.float32(s)
            inp[..., dataset.radiance_channels(meta["channels"])] *= np.float32(s)
            if (ref_path, s) not in ref_exposures:
                ref_exposures[(ref_path, s)] = contract.evaluation_exposure(ref)
            exposure = meta["exposures"][0] if s == 1.0 else contract.exposure(inp[..., :3])
            h, w = ref.shape[:2]
            c = min(h, w) // 16 * 16
            y0, x0 = (h - c) // 2, (w - c) // 2
            a = to(inp[y0 : y0 + c, x0 : x0 + c])
            b = to(ref[y0 : y0 + c, x0 : x0 + c])
            pred, exp = net.transferred(a, torch.tensor([exposure]))
            total += float(objective(net, pred, exp, b, torch.tensor([ref_exposures[(ref_path, s)]]), cfg))
            n += 1
    return total / max(n, 1)


def main(argv=None):
    cfg = config.parse(argv, __doc__.split("\n\n")[0])
    torch.manual_seed(cfg.seed)
    torch.set_num_threads(cfg.threads)
    # A CUDA GPU is used when present (PRESET=full on a GPU machine); CPU otherwise.
    device = torch.device("cuda" if torch.cuda.is_available() else "cpu")
    torch.backends.cudnn.benchmark = device.type == "cuda"  # the crops' shape never changes
    run = Path(cfg.run_dir)
    ckpt = run / "checkpoint.pt"
    try:
        net = model.denoiser(cfg).to(device=device, memory_format=torch.channels_last)
    except ValueError as e:
        raise SystemExit(f"train: {e}")
    opt = torch.optim.Adam(net.parameters(), lr=cfg.lr)
    if cfg.loss not in LOSSES:
        raise SystemExit(f"train: --loss {cfg.loss!r}: expected " + " or ".join(LOSSES))
    if cfg.schedule not in ("steps", "time"):
        raise SystemExit(f"train: --schedule {cfg.schedule!r}: expected steps or time")
    by_time = cfg.schedule == "time"
    if by_time:
        sched = TimeOneCycle(opt, cfg.lr, cfg.steps, cfg.minutes * 60)
    else:
        sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=cfg.lr, total_steps=cfg.steps, pct_start=0.15)
    dtype = autocast_dtype(device, cfg.precision)
    step, earlier_seconds, resumed_at = 0, 0.0, []
    if cfg.init_from and not (cfg.resume and ckpt.exists()):
        try:
            net.load_state_dict(grow.initial_weights(cfg.init_from, cfg))
        except RuntimeError as e:
            raise SystemExit(
                f"train: --init-from {cfg.init_from}: weights of another network ({str(e).splitlines()[0]})"
            )
        print(f"weights from {cfg.init_from}")
    if cfg.resume and ckpt.exists():
        saved = config.Config.load(run / "config.json") if (run / "config.json").exists() else cfg
        if saved.schedule != cfg.schedule:  # the other kind's state would silently restart the cycle
            raise SystemExit(f"train: --resume {run}: the run's schedule is {saved.schedule!r}, not {cfg.schedule!r}")
        if saved.loss != cfg.loss:  # Adam's moments and the record would belong to the other objective
            raise SystemExit(f"train: --resume {run}: the run's loss is {saved.loss!r}, not {cfg.loss!r}")
        if any(getattr(saved, k) != getattr(cfg, k) for k in config.NETWORK):  # its weights would not load
            raise SystemExit(
                f"train: --resume {run}: the run trains "
                + ", ".join(f"{k} {getattr(saved, k)}" for k in config.NETWORK)
                + "; this one "
                + ", ".join(f"{k} {getattr(cfg, k)}" for k in config.NETWORK)
            )
        state = torch.load(ckpt, weights_only=False, map_location=device)
        net.load_state_dict(state["model"])
        opt.load_state_dict(state["optimizer"])
        sched.load_state_dict(state["scheduler"])
        step = state["step"]
        earlier_seconds, resumed_at = state.get("seconds", 0.0), state.get("resumed_at", []) + [step]
        print(f"resumed at step {step}")
    # As many crops as the remaining steps take (a fixed length once ended runs of more than
    # 100 000 / batch steps early, before the schedule had annealed).
    try:
        data = dataset.Crops(
            Path(cfg.prep_dir) / "train",
            cfg.crop,
            cfg.seed,
            start=step * cfg.batch,
            length=max(cfg.steps - step, 0) * cfg.batch,
            noisy_spp=cfg.noisy_spp,
            dle_paths=cfg.dle_paths,
            extra_seeds=cfg.extra_seeds,
            extra_spp=cfg.extra_spp,
            own_features=cfg.own_features,
            mean_luminance=config.scale_luminance(cfg),
        )
    except FileNotFoundError as e:  # before the run directory is written
        raise SystemExit(f"train: {e}")
    run.mkdir(parents=True, exist_ok=True)
    cfg.save(run / "config.json")
    loader = batches(data, cfg, device)
    start = time.time()
    log = open(run / "log.jsonl", "a")
    # On stderr: a line redrawn on a terminal, a line every LUXEST_PROGRESS_INTERVAL seconds in
    # make's output or Slurm's slurm-<job>.out (progress.py); every 50 steps in <run>/log.jsonl.
    budget = cfg.minutes * 60 - (earlier_seconds if by_time else 0.0)
    shown = progress.Progress("train", cfg.steps, "steps", done=step, budget=max(budget, 0.0) or None)
    net.train()
    for a, b, e, e_ref in loader:
        if by_time:  # the budget of all runs together: the cycle ends with it
            elapsed = earlier_seconds + time.time() - start
            if sched.done(step, elapsed):
                break
            sched.at(step, elapsed)
        elif step >= cfg.steps or time.time() - start > cfg.minutes * 60:
            break
        a = a.to(device=device, memory_format=torch.channels_last)
        b, e, e_ref = b.to(device), e.to(device), e_ref.to(device)
        with torch.autocast(device.type, dtype=dtype or torch.bfloat16, enabled=dtype is not None):
            pred, exp = net.transferred(a, e)
        value = objective(net, pred, exp, b, e_ref, cfg)
        opt.zero_grad()
        value.backward()
        opt.step()
        if not by_time:
            sched.step()
        step += 1
        status = None  # the loss as logged: reading it every step would wait for a GPU's step
        if step % 50 == 0 or step == 1:
            rec = {
                "step": step,
                "loss": float(value.detach()),
                "lr": sched.get_last_lr()[0],
                "seconds": time.time() - start,
            }
            log.write(json.dumps(rec) + "\n")
            log.flush()
            status = f"loss {rec['loss']:.4f}"
        shown.update(1, status)
        if step % cfg.checkpoint_every == 0:
            save(net, opt, sched, step, earlier_seconds + time.time() - start, resumed_at, ckpt)
    shown.close()
    save(net, opt, sched, step, earlier_seconds + time.time() - start, resumed_at, ckpt)
    net.eval()
    v = validation_loss(net.cpu(), cfg.prep_dir, cfg)
    summary = {
        "steps": step,
        "seconds": earlier_seconds + time.time() - start,
        "resumed_at": resumed_at,
        "valid_loss": v,
        "device": device.type,
        "autocast": "bf16" if dtype is not None else "fp32",
    }
    (run / "summary.json").write_text(json.dumps(summary, indent=2))
    # What models/<dataset>.config.json records: the configuration and how the run went.
    (run / "run.json").write_text(json.dumps({**asdict(cfg), "run": summary}, indent=2))
    print(f"train: {step} steps in {summary['seconds']:.0f} s of training, validation loss {v:.4f}")


def save(net, opt, sched, step, seconds, resumed_at, path):
    """A checkpoint: weights, optimiser and schedule state, the step, the training seconds of all
    runs so far and the steps at which it was resumed. Written to a temporary name and renamed,
    so that a run killed while saving (scancel, pre-emption) leaves the previous checkpoint."""
    tmp = Path(path).with_name(f".{Path(path).name}.tmp-{os.getpid()}")
    torch.save(
        {
            "model": net.state_dict(),
            "optimizer": opt.state_dict(),
            "scheduler": sched.state_dict(),
            "step": step,
            "seconds": seconds,
            "resumed_at": resumed_at,
        },
        tmp,
    )
    os.replace(tmp, path)


if __name__ == "__main__":
    main()
