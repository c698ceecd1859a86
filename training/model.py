"""The denoiser: an OIDN-style U-Net (4 levels of 3x3 convolutions + ReLU, max-pool down,
nearest up-sampling, skip connections) on the transferred hdr + albedo + normal (9 channels),
with one of two outputs (`Config.head`):

- `kpn` (the default): a multi-scale kernel-predicting output (Bako et al. 2017, "Kernel-
  Predicting Convolutional Networks for Denoising Monte Carlo Renderings"; Vogels et al. 2018,
  "Denoising with Kernel Prediction and Asymmetric Loss Functions"). The noisy radiance is
  demodulated by the albedo (irradiance = hdr / max(albedo, ALBEDO_FLOOR)), averaged down to
  1/2, 1/4 and 1/8 of the image side (and 1/16 with `Config.scales` 5, its kernels predicted
  from the bottleneck), and at every scale each pixel is replaced by a weighted
  mean of its KERNEL x KERNEL neighbours, the weights a softmax of what the decoder level of that
  scale predicts (so they are positive and sum to one). From the coarsest scale up, a predicted
  per-pixel blend alpha replaces the finer scale's low frequencies by the coarser result:
  o_s = f_s + alpha_s (U(o_{s+1}) - U(D(f_s))). The result is remodulated by the same albedo.
  At every scale the filtered image is a local weighted mean of the input's irradiance (the
  blend of the scales is not a convex combination; the output is clamped at zero); a noiseless
  image of uniform irradiance comes back unchanged whatever the weights, and the identity kernel
  with alpha 0 returns any input unchanged, which is what a clean input needs.
  With `detail_gate` (`Config.detail_gate`) each finer scale also predicts how much of its own
  filtered detail to keep, beta_s = sigmoid(one more logit) in [0, 1]:
  o_s = U(D(f_s)) + beta_s (f_s - U(D(f_s))) + alpha_s (U(o_{s+1}) - U(D(f_s))). Without it
  (beta = 1) the detail band of a 5x5 weighted mean of the noisy irradiance is always kept, a
  floor on the noise left on flat surfaces at low spp (docs/measurements.md, *A fourth GPU
  run*); with beta 0 and alpha 1 a pixel takes the coarser result alone (bilinear). A uniform
  image and the identity (beta 1, alpha 0, identity kernel) still come back unchanged.
- `direct`: the U-Net predicts the transferred radiance itself (the first models).

With the `emi` feature (aov-write's emitted radiance seen directly, the fourth input, `Config.
features`), the network filters only what the emitters do not emit straight at the camera: its
radiance input is hdr - emi (clamped at zero), and the emission is added back unfiltered, so the
light sources, many times brighter than what they light, keep their radiance and colour (the
models without the feature lost 2-3 % of the image's mean at the light). The network also sees
the transferred emi as three more channels (where the emitters are). Only the `kpn` head takes
it. (Tried and dropped, 2026-11-24: filtering the emission by a kernel of its own from one more
1x1 head, to antialias the emitter's edge at low spp; step-matched on the quick dataset it
scored 0.1-0.9 dB below adding it back unfiltered at 1-64 spp on the Cornell box, 2.2 dB at 1024
spp.) With the `ema` feature as well (the fifth input: the emission over at least aov-write's
--min-samples, antialiased like the albedo), that is what is added back, while emi, the image's
own samples, is still what is subtracted: at 1 spp an emitter's edge pixel has either all or none
of the emitter's radiance in hdr and emi, and the fraction it covers in ema.

Both heads are scale-equivariant through the exposure input: hdr times s with the exposure over
s gives the network the same input and the result times s (denoise's rescaling near the f32
limit relies on it). The autoexposure is not, near its 1e-4 floor: callers brighten a dim image
first (luxest_contract.dim_exponent). `Denoiser` wraps either with the transfer of transfer.py and the padding to
multiples of 16, so
the exported graph takes raw linear features of any H, W, plus the exposure of the whole image
(computed by the caller over the whole image, so that tiles of one image share it:
luxest_contract.exposure). Training passes the stored whole-image exposure of each crop's image
(preprocess.py), so the network is trained on exactly the inputs it sees at inference."""
import torch
import torch.nn as nn
import torch.nn.functional as F

import luxest_contract as contract
import transfer

HEADS = ("kpn", "direct")
KERNEL = 5
"""Side of the per-pixel filter kernels of the `kpn` head, at every scale."""
SCALES = 4
"""Scales of the `kpn` head by default: 1, 1/2, 1/4, 1/8 (the U-Net's decoder levels); a network
of `scales` 5 (Config.scales) filters at 1/16 too (the bottleneck's level)."""
DETAIL_GATE_INIT = 5.0
"""The bias of a detail gate's logit added to a model trained without gates (`add_detail_gates`):
beta = sigmoid(5) = 0.993, so the fine-tuning starts within 0.7 % of the detail band of the
model it starts from."""
ALBEDO_FLOOR = 0.01
"""Demodulation divides by max(albedo, ALBEDO_FLOOR) and remodulates by the same value, so a
black albedo (background, black materials) neither divides by zero nor changes the result when
the kernel is the identity."""


def conv(cin, cout):
    return nn.Sequential(nn.Conv2d(cin, cout, 3, padding=1), nn.ReLU(inplace=True))


class UNet(nn.Module):
    """`forward` returns the output channels at full resolution (`direct`), `decoder` the
    decoder's feature maps at 1, 1/2, 1/4, 1/8 of the side and the bottleneck's at 1/16 (`kpn`)."""

    def __init__(self, in_channels=9, out_channels=3, width=24):
        super().__init__()
        c1, c2, c3, c4, c5 = width, width * 3 // 2, width * 2, width * 5 // 2, width * 3
        self.channels = (c1, c2, c3, c4, c5)
        self.enc0 = nn.Sequential(conv(in_channels, c1), conv(c1, c1))
        self.enc1 = conv(c1, c2)
        self.enc2 = conv(c2, c3)
        self.enc3 = conv(c3, c4)
        self.bottleneck = conv(c4, c5)
        self.dec3 = nn.Sequential(conv(c5 + c4, c4), conv(c4, c4))
        self.dec2 = nn.Sequential(conv(c4 + c3, c3), conv(c3, c3))
        self.dec1 = nn.Sequential(conv(c3 + c2, c2), conv(c2, c2))
        self.dec0 = nn.Sequential(conv(c2 + c1, c1), conv(c1, c1))
        self.out = nn.Conv2d(c1, out_channels, 3, padding=1) if out_channels else None
        self.joins = None  # split_joins (export)

    def decoder(self, x):
        e0 = self.enc0(x)                      # H
        e1 = self.enc1(F.max_pool2d(e0, 2))    # H/2
        e2 = self.enc2(F.max_pool2d(e1, 2))    # H/4
        e3 = self.enc3(F.max_pool2d(e2, 2))    # H/8
        b = self.bottleneck(F.max_pool2d(e3, 2))  # H/16
        d3 = self.join("dec3", b, e3)    # H/8
        d2 = self.join("dec2", d3, e2)   # H/4
        d1 = self.join("dec1", d2, e1)   # H/2
        d0 = self.join("dec0", d1, e0)   # H
        return [d0, d1, d2, d3, b]

    def join(self, name, coarse, skip):
        """Decoder block `name` over the concatenation of `coarse` upsampled (nearest) and
        `skip`; after `split_joins` as a sum of two convolutions instead (same function)."""
        block = getattr(self, name)
        up = F.interpolate(coarse, scale_factor=2.0, mode="nearest")
        if self.joins is None:
            return block(torch.cat([up, skip], 1))
        conv = block[0][0]
        y = (F.conv2d(up, self.joins[name + "_up"], conv.bias, padding=1)
             + F.conv2d(skip, self.joins[name + "_skip"], None, padding=1))
        return block[1:](F.relu(y))

    def split_joins(self):
        """For export (export.py): each decoder block's first convolution over [upsampled,
        skip] becomes the sum of one convolution per part, with the weight's two halves as
        parameters `joins.<block>_up` / `_skip` (the whole weight then is not in the graph;
        export.load_onnx joins them again). The same function up to float rounding, and no
        Concat node, which ONNX Runtime runs outside its blocked-channel layout with a reordering
        before and after. Export only: the halves are copies, so a split network is not trained
        or loaded into afterwards."""
        joins = {}
        for name, skip in zip(("dec3", "dec2", "dec1", "dec0"), reversed(self.channels[:4])):
            w = getattr(self, name)[0][0].weight.detach()
            c = w.shape[1] - skip
            joins[name + "_up"] = nn.Parameter(w[:, :c].clone(), requires_grad=False)
            joins[name + "_skip"] = nn.Parameter(w[:, c:].clone(), requires_grad=False)
        self.joins = nn.ParameterDict(joins)

    def forward(self, x):
        return self.out(self.decoder(x)[0])


def apply_kernels(img, logits, gather="unfold"):
    """Each pixel of `img` (N, C, H, W) replaced by the mean of its KERNEL x KERNEL neighbours
    (replicated at the border) weighted by softmax(`logits` (N, KERNEL², H, W)) over the kernel:
    sum(e_i x_i) / sum(e_i) with e_i = exp(logit_i - max logit), normalised after the sum (C
    divisions per pixel, not KERNEL²). The neighbours come from unfold (training: the KERNEL²
    slices' gradients would be zero-filled full tensors, five times the cost of a step) or from
    KERNEL² slices (export: ONNX Runtime runs unfold's decomposition through Gather, slower)."""
    e = torch.exp(logits - logits.amax(1, keepdim=True))
    r = KERNEL // 2
    n, c, h, wd = img.shape
    p = F.pad(img, (r, r, r, r), mode="replicate")
    if gather == "unfold":
        num = (F.unfold(p, KERNEL).view(n, c, KERNEL * KERNEL, h, wd) * e.unsqueeze(1)).sum(2)
    else:
        num = None
        for i in range(KERNEL * KERNEL):
            dy, dx = divmod(i, KERNEL)
            term = e[:, i:i + 1] * p[:, :, dy:dy + h, dx:dx + wd]
            num = term if num is None else num + term
    return num / e.sum(1, keepdim=True)


def reconstruct(hdr, albedo, heads, gather="unfold", detail_gate=False):
    """The `kpn` output (linear radiance) from the linear hdr and albedo (N, 3, H, W; H and W
    multiples of 2^(len(heads) - 1)) and the heads' predictions per scale, finest first: (N, KERNEL²
    [+ 1 blend logit (+ 1 detail-gate logit with `detail_gate`) except at the coarsest], H_s,
    W_s). In float32 whatever the autocast."""
    with torch.autocast(hdr.device.type, enabled=False):
        a = albedo.float().clamp(min=ALBEDO_FLOOR)
        irr = [hdr.float().clamp(min=0) / a]
        for _ in range(1, len(heads)):
            irr.append(F.avg_pool2d(irr[-1], 2))
        up = lambda t: F.interpolate(t, scale_factor=2.0, mode="bilinear", align_corners=False)
        k2 = KERNEL * KERNEL
        out = apply_kernels(irr[-1], heads[-1][:, :k2].float(), gather)
        for s in range(len(heads) - 2, -1, -1):
            pred = heads[s].float()
            f = apply_kernels(irr[s], pred[:, :k2], gather)
            alpha = torch.sigmoid(pred[:, k2:k2 + 1])
            low = up(F.avg_pool2d(f, 2))
            if detail_gate:  # beta f + (1 - beta) U(D(f)): exactly f where beta is 1
                beta = torch.sigmoid(pred[:, k2 + 1:k2 + 2])
                f = beta * f + (1 - beta) * low
            out = f + alpha * (up(out) - low)
        # The blend is not a convex combination (a dark pixel beside a firefly can go below
        # zero); the loss sees max(out, 0) through the transfer, and so does the graph.
        return (out * a).clamp(min=0)


FEATURE_SETS = tuple(contract.FEATURES[:n] for n in (3, 4, 5))
"""The input features a model can take, in channel order (3 channels each): hdr, alb, nrm, then
emi and ema (luxest_contract.FEATURES). `ema` (the emission
antialiased, aov-write --min-samples) is only added back, in place of `emi`; the network does not
see it, so a model with it has the weights of one without it."""


def head_outputs(scale, detail_gate, scales=SCALES):
    """Outputs of the `kpn` head's 1x1 convolution at `scale` (0 the finest) of `scales`: the
    KERNEL² kernel logits, and at every finer scale the blend logit and, with detail gates, the
    gate's."""
    return KERNEL * KERNEL + ((2 if detail_gate else 1) if scale < scales - 1 else 0)


def scales_of(state):
    """The `kpn` scales of a state dict (its heads)."""
    return sum(1 for k in state if k.startswith("heads.") and k.endswith(".weight"))


def has_detail_gates(state):
    """Whether a `kpn` state dict's heads predict detail gates (their first head's outputs)."""
    w = state.get("heads.0.weight")
    return w is not None and w.shape[0] == head_outputs(0, True)


def add_detail_gates(state):
    """A `kpn` state dict without detail gates with them added: one more output of every finer
    scale's 1x1 head, weights 0 and bias DETAIL_GATE_INIT (beta = 0.993 everywhere), the rest
    unchanged, for a fine-tuning with `detail_gate` that starts from a model without it."""
    state = dict(state)
    scales = scales_of(state)
    for s in range(scales - 1):
        w, b = state[f"heads.{s}.weight"], state[f"heads.{s}.bias"]
        if w.shape[0] != head_outputs(s, False, scales):
            raise ValueError(f"heads.{s}: {w.shape[0]} outputs, expected {head_outputs(s, False, scales)} (no detail gate)")
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
    old = denoiser(cfg).unet.channels
    torch.manual_seed(seed)
    net = Denoiser(width=to_width, head=cfg.head, features=cfg.features, detail_gate=cfg.detail_gate, scales=cfg.scales)
    new = net.unet.channels
    fresh = net.state_dict()
    c1, c2, c3, c4, c5 = range(5)
    # The input channel groups of each convolution (levels; None: the network's input), in the
    # order they are concatenated (UNet.join: the upsampled coarse level first, then the skip).
    inputs = {"enc0.0": [None], "enc0.1": [c1], "enc1": [c1], "enc2": [c2], "enc3": [c3],
              "bottleneck": [c4], "dec3.0": [c5, c4], "dec3.1": [c4], "dec2.0": [c4, c3],
              "dec2.1": [c3], "dec1.0": [c3, c2], "dec1.1": [c2], "dec0.0": [c2, c1], "dec0.1": [c1]}
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
                w[:n_out, o_new:o_new + n_old] = src[:, o_old:o_old + n_old]
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
    if w.shape[0] != head_outputs(3, detail_gate, 4):
        raise ValueError(f"heads.3: {w.shape[0]} outputs, expected {head_outputs(3, detail_gate, 4)}")
    extra = [-DETAIL_GATE_INIT] + ([DETAIL_GATE_INIT] if detail_gate else [])
    state["heads.3.weight"] = torch.cat([w, torch.zeros_like(w[:1]).repeat(len(extra), 1, 1, 1)])
    state["heads.3.bias"] = torch.cat([b, torch.tensor(extra, dtype=b.dtype)])
    c5 = state["unet.bottleneck.0.weight"].shape[0]
    state["heads.4.weight"] = torch.zeros(head_outputs(4, detail_gate, 5), c5, 1, 1, dtype=w.dtype)
    state["heads.4.bias"] = torch.zeros(head_outputs(4, detail_gate, 5), dtype=b.dtype)
    return state


def denoiser(cfg):
    """The Denoiser of a configuration (config.Config): width, head, features, detail gate."""
    return Denoiser(width=cfg.base_width, head=cfg.head, features=cfg.features, detail_gate=cfg.detail_gate,
                    scales=cfg.scales)


class Denoiser(nn.Module):
    """Raw linear (N, 3 x len(features), H, W) hdr+alb+nrm[+emi] -> linear (N, 3, H, W)
    radiance."""

    def __init__(self, width=24, head="kpn", features=FEATURE_SETS[0], detail_gate=False, scales=SCALES):
        super().__init__()
        if scales not in (4, 5):
            raise ValueError(f"scales {scales}: expected 4 or 5")
        if scales != SCALES and head != "kpn":
            raise ValueError(f"{scales} scales need the kpn head")
        self.scales = scales
        if head not in HEADS:
            raise ValueError(f"head {head!r}: expected one of {', '.join(HEADS)}")
        features = tuple(features)
        if features not in FEATURE_SETS:
            raise ValueError(f"features {', '.join(features)}: expected one of "
                             + "; ".join(", ".join(f) for f in FEATURE_SETS))
        self.emission = "emi" in features
        if self.emission and head != "kpn":
            raise ValueError("the emi feature needs the kpn head")
        if detail_gate and head != "kpn":
            raise ValueError("the detail gate needs the kpn head (--no-detail-gate)")
        self.detail_gate = bool(detail_gate)
        self.features = features
        self.in_channels = 3 * len(features)
        # The channel of the emission added back: ema where the model takes it, else emi.
        self.added_emission = 3 * features.index("ema" if "ema" in features else "emi") if self.emission else None
        network_channels = 3 * len([f for f in features if f != "ema"])
        self.head = head
        self.kernel_gather = "unfold"  # export.py sets "slices" (apply_kernels)
        if head == "direct":
            self.unet = UNet(in_channels=network_channels, width=width)
        else:
            self.unet = UNet(in_channels=network_channels, width=width, out_channels=0)
            self.heads = nn.ModuleList(nn.Conv2d(c, head_outputs(s, self.detail_gate, scales), 1)
                                       for s, c in enumerate(self.unet.channels[:scales]))

    def forward(self, x, exposure=None):
        """`exposure` (N,) float: the exposure of each whole image; if None, x must hold whole
        images and it is computed from them (transfer.exposure_of)."""
        h, w = x.shape[2], x.shape[3]
        if exposure is None:
            exposure = transfer.exposure_of(x[:, 0:3]).to(x.device)
        ph, pw = (16 - h % 16) % 16, (16 - w % 16) % 16
        x = F.pad(x, (0, pw, 0, ph), mode="replicate")
        out, exp = self.transferred(x, exposure)
        out = out[:, :, :h, :w]
        return self.linear(out, exp)

    def transferred(self, x, exposure):
        """(output, exposure as (N, 1, 1, 1)) for x of H, W multiples of 16. `exposure` (N,):
        that of each crop's whole image (never the crop's own). The output is the transferred
        radiance for `direct`, linear radiance for `kpn`; `loss_domain` maps it to the
        transferred domain of the loss."""
        hdr = x[:, 0:3]
        exp = exposure.view(-1, 1, 1, 1).to(x.dtype)
        parts = [None, x[:, 3:9]]
        if self.emission:
            emi = x[:, 9:12]
            hdr = (hdr - emi).clamp(min=0)
            parts.append(transfer.forward(emi, exp))
        parts[0] = transfer.forward(hdr, exp)
        inp = torch.cat(parts, 1)
        if self.head == "direct":
            return self.unet(inp), exp
        feats = self.unet.decoder(inp)
        # The 1x1 heads in float32 (cheap): bf16 logits of 10-30 are rounded by 0.06-0.125,
        # several per cent of a kernel weight, which inference in float32 would not see.
        with torch.autocast(x.device.type, enabled=False):
            heads = [head(f.float()) for head, f in zip(self.heads, feats)]
            out = reconstruct(hdr, x[:, 3:6], heads, self.kernel_gather, self.detail_gate)
            if self.emission:
                a = self.added_emission
                out = out + x[:, a:a + 3].float().clamp(min=0)
        return out, exp

    def linear(self, out, exp):
        """The output of `transferred` as linear radiance (what the exported model returns)."""
        return transfer.inverse(out, exp) if self.head == "direct" else out

    def loss_domain(self, out, exp):
        """The output of `transferred` in the transferred domain (where the loss is taken)."""
        return out if self.head == "direct" else transfer.forward(out, exp.float())
