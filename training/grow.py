"""Starting a training run from a smaller model's weights (train.py --init-from): a `kpn` model
grows into the run's network computing the same function, or nearly. Detail gates are added
(`add_detail_gates`: gates that keep 0.993 of the detail), a fifth scale (`add_coarsest_scale`:
a blend that takes 0.007 of the coarser band), more channels (`widen`: new channels that feed
nothing until trained), so that a fine-tuning starts where the model it grows from stands."""

from dataclasses import asdict
from pathlib import Path

import torch

import config
import model

DETAIL_GATE_INIT = 5.0
"""The bias of a detail gate's logit added to a model trained without gates (`add_detail_gates`):
beta = sigmoid(5) = 0.993, so the fine-tuning starts within 0.7 % of the detail band of the
model it starts from."""


def scales_of(state):
    """The `kpn` scales of a state dict (its heads)."""
    return sum(1 for k in state if k.startswith("heads.") and k.endswith(".weight"))


def has_detail_gates(state):
    """Whether a `kpn` state dict's heads predict detail gates (their first head's outputs)."""
    w = state.get("heads.0.weight")
    return w is not None and w.shape[0] == model.head_outputs(0, True)


def add_detail_gates(state):
    """A `kpn` state dict without detail gates with them added: one more output of every finer
    scale's 1x1 head, weights 0 and bias DETAIL_GATE_INIT (beta = 0.993 everywhere), the rest
    unchanged, for a fine-tuning with `detail_gate` that starts from a model without it."""
    state = dict(state)
    scales = scales_of(state)
    for s in range(scales - 1):
        w, b = state[f"heads.{s}.weight"], state[f"heads.{s}.bias"]
        if w.shape[0] != model.head_outputs(s, False, scales):
            raise ValueError(
                f"heads.{s}: {w.shape[0]} outputs, expected {model.head_outputs(s, False, scales)} (no detail gate)"
            )
        state[f"heads.{s}.weight"] = torch.cat([w, torch.zeros_like(w[:1])])
        state[f"heads.{s}.bias"] = torch.cat([b, torch.full_like(b[:1], DETAIL_GATE_INIT)])
    return state


def widen(state, cfg, to_width, seed=0):
    """A `kpn` state dict of the network of `cfg` (config.Config) as one of U-Net width
    `to_width` computing the same function (Net2Net-style, Chen et al. 2016, with zero fan-out
    instead of splitting): every level's old channels keep their weights and come first; each
    new channel gets the default initialisation of a fresh convolution (seeded) for its inputs
    and bias, and weight zero wherever it feeds an old channel or a head, so the output is
    unchanged until training moves those zeros (their gradients are not zero: the new channels
    are active). For a fine-tuning with more capacity, at the wider network's inference cost."""
    if cfg.head != "kpn":
        raise ValueError(f"widen: a {cfg.head} model (only kpn)")
    if to_width < cfg.base_width:
        raise ValueError(f"widen: cannot narrow a width-{cfg.base_width} network to {to_width}")
    old = model.denoiser(cfg).unet.channels
    torch.manual_seed(seed)
    net = model.Denoiser(
        width=to_width, head=cfg.head, features=cfg.features, detail_gate=cfg.detail_gate, scales=cfg.scales
    )
    new = net.unet.channels
    fresh = net.state_dict()
    c1, c2, c3, c4, c5 = range(5)
    # The input channel groups of each convolution (levels; None: the network's input), in the
    # order they are concatenated (UNet.join: the upsampled coarse level first, then the skip).
    inputs = {
        "enc0.0": [None],
        "enc0.1": [c1],
        "enc1": [c1],
        "enc2": [c2],
        "enc3": [c3],
        "bottleneck": [c4],
        "dec3.0": [c5, c4],
        "dec3.1": [c4],
        "dec2.0": [c4, c3],
        "dec2.1": [c3],
        "dec1.0": [c3, c2],
        "dec1.1": [c2],
        "dec0.0": [c2, c1],
        "dec0.1": [c1],
    }
    inputs.update({f"heads.{s}": [s] for s in range(cfg.scales)})
    out = {}
    for key, w in fresh.items():
        if key not in state:
            raise ValueError(f"widen: the weights lack {key}")
        src = state[key]
        if key.startswith("heads."):
            name = key.rsplit(".", 1)[0]
        else:
            name = key.removeprefix("unet.").rsplit(".", 1)[0].removesuffix(".0")
        w = w.clone()
        n_out = src.shape[0]
        if key.endswith("bias"):
            w[:n_out] = src
        else:
            w[:n_out] = 0  # an old output: its old weights, zero from every new input
            o_new = o_old = 0
            for level in inputs[name]:
                # The network's input (its channels, not widened) or a level's channels.
                n_old, n_new = (src.shape[1],) * 2 if level is None else (old[level], new[level])
                w[:n_out, o_new : o_new + n_old] = src[:, o_old : o_old + n_old]
                o_new, o_old = o_new + n_new, o_old + n_old
            if o_old != src.shape[1] or o_new != w.shape[1]:
                raise ValueError(f"widen: {key}: {src.shape[1]} inputs, expected {o_old}")
        out[key] = w
    return out


def add_coarsest_scale(state, detail_gate):
    """A 4-scale `kpn` state dict as a 5-scale one (Config.scales): the 1/8 head gains a blend
    logit (weights 0, bias -DETAIL_GATE_INIT: alpha = 0.007 everywhere) and, with detail gates, a
    gate logit (weights 0, bias DETAIL_GATE_INIT: beta = 0.993), and a new 1/16 head on the
    bottleneck predicts zero logits (a uniform 5x5 mean). The output starts within 0.7 % of the
    1/8 scale's detail and coarse bands of the 4-scale model's, and the new logits learn from the
    first step (the sigmoids' slopes there are 0.007, not zero)."""
    if scales_of(state) != 4:
        raise ValueError(f"add_coarsest_scale: a model of {scales_of(state)} scales (expected 4)")
    state = dict(state)
    w, b = state["heads.3.weight"], state["heads.3.bias"]
    if w.shape[0] != model.head_outputs(3, detail_gate, 4):
        raise ValueError(f"heads.3: {w.shape[0]} outputs, expected {model.head_outputs(3, detail_gate, 4)}")
    extra = [-DETAIL_GATE_INIT] + ([DETAIL_GATE_INIT] if detail_gate else [])
    state["heads.3.weight"] = torch.cat([w, torch.zeros_like(w[:1]).repeat(len(extra), 1, 1, 1)])
    state["heads.3.bias"] = torch.cat([b, torch.tensor(extra, dtype=b.dtype)])
    c5 = state["unet.bottleneck.0.weight"].shape[0]
    state["heads.4.weight"] = torch.zeros(model.head_outputs(4, detail_gate, 5), c5, 1, 1, dtype=w.dtype)
    state["heads.4.bias"] = torch.zeros(model.head_outputs(4, detail_gate, 5), dtype=b.dtype)
    return state


def initial_weights(path, cfg):
    """The state dict of `path` (a model exported by export.py, or a run's checkpoint.pt) for a
    run of `cfg`: a fine-tuning starts from it with its own schedule. A `kpn` model may grow into
    the run's network: without detail gates it gets them (add_detail_gates), with 4 scales a
    fifth (add_coarsest_scale), and an exported one of smaller width is widened (widen, the
    same function). Any other difference of network is refused in one line."""
    import export

    path = Path(path)
    if not path.is_file():
        raise SystemExit(f"train: --init-from {path}: no such file")
    if path.suffix == ".onnx":
        src, state = export.load_onnx(path)
    else:
        src = None
        state = torch.load(path, weights_only=False, map_location="cpu")["model"]
    if src is not None:
        grows = src.head == cfg.head == "kpn" and src.base_width <= cfg.base_width and src.scales <= cfg.scales
        if (src.head, list(src.features)) != (cfg.head, list(cfg.features)) or (
            (src.base_width, src.scales) != (cfg.base_width, cfg.scales) and not grows
        ):
            raise SystemExit(
                f"train: --init-from {path}: a width-{src.base_width} {src.head} model of {src.scales} scales "
                f"on {','.join(src.features)}, this run trains width {cfg.base_width} {cfg.head} of "
                f"{cfg.scales} scales on {','.join(cfg.features)}"
            )
    if cfg.head == "kpn" and "heads.0.weight" in state:
        gated = has_detail_gates(state)
        if gated and not cfg.detail_gate:
            raise SystemExit(
                f"train: --init-from {path}: a model with detail gates, this run trains one without (--detail-gate)"
            )
        if cfg.detail_gate and not gated:
            try:
                state = add_detail_gates(state)
            except ValueError as e:
                raise SystemExit(f"train: --init-from {path}: weights of another network ({e})")
            print(f"detail gates added to the weights of {path} (bias {DETAIL_GATE_INIT})")
        if scales_of(state) < cfg.scales:
            state = add_coarsest_scale(state, cfg.detail_gate)
            print(f"a fifth scale (1/16) added to the weights of {path} (blend bias -{DETAIL_GATE_INIT})")
        if src is not None and src.base_width < cfg.base_width:
            grown = config.Config.from_values({**asdict(src), "detail_gate": cfg.detail_gate, "scales": cfg.scales})
            state = widen(state, grown, cfg.base_width, seed=0)  # one init for all runs: soupable
            print(
                f"widened the width-{src.base_width} weights of {path} to width {cfg.base_width} "
                "(same function: new channels feed nothing until trained; grow.widen)"
            )
    return state
