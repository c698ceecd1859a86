"""The denoiser: an OIDN-style U-Net (4 levels of 3x3 convolutions + ReLU, max-pool down,
nearest up-sampling, skip connections) on the transferred features, with one of two outputs
(`Config.head`):

- `kpn` (the default): multi-scale kernel prediction (Bako et al. 2017, "Kernel-Predicting
  Convolutional Networks for Denoising Monte Carlo Renderings"; Vogels et al. 2018, "Denoising
  with Kernel Prediction and Asymmetric Loss Functions"). The noisy radiance is demodulated by
  the albedo (irradiance = hdr / max(albedo, ALBEDO_FLOOR)), averaged down to 1/2, 1/4 and 1/8
  of the image side (and 1/16 with `Config.scales` 5, its kernels predicted from the
  bottleneck), and at every scale each pixel is replaced by a weighted mean of its KERNEL x
  KERNEL neighbours, the weights a softmax of what the decoder level of that scale predicts.
  From the coarsest scale up, a predicted per-pixel blend alpha replaces the finer scale's low
  frequencies by the coarser result: o_s = f_s + alpha_s (U(o_{s+1}) - U(D(f_s))). With
  `detail_gate` (`Config.detail_gate`) each finer scale also predicts how much of its own
  filtered detail to keep, beta_s in [0, 1]:
  o_s = U(D(f_s)) + beta_s (f_s - U(D(f_s))) + alpha_s (U(o_{s+1}) - U(D(f_s))); without it
  (beta = 1) the detail band of a 5x5 weighted mean of the noisy irradiance is always kept, a
  floor on the noise left on flat surfaces at low spp (docs/measurements.md, *A fourth GPU
  run*); with beta 0 and alpha 1 a pixel takes the coarser result alone (bilinear). The result
  is remodulated by the same albedo and clamped at zero (the blend is not a convex
  combination). Whatever the weights, a noiseless image of uniform irradiance comes back
  unchanged; the identity kernel with alpha 0 (and beta 1) returns any input unchanged, which is
  what a clean input needs.
- `direct`: the U-Net predicts the transferred radiance itself.

With the `emi` feature (aov-write's emitted radiance seen directly; `kpn` only) the network
filters only what the emitters do not emit straight at the camera: its radiance input is
max(hdr - emi, 0), it sees the transferred emi as three more channels, and the emission is added
back unfiltered, so the light sources keep their radiance, colour and edge. With the `ema`
feature as well (the emission over at least aov-write's --min-samples, antialiased like the
albedo), ema is what is added back while emi, the image's own samples, is still what is
subtracted: at 1 spp an emitter's edge pixel has all or none of its radiance in hdr and emi, and
the fraction it covers in ema.

`Denoiser` wraps either head with the transfer of transfer.py and the padding to multiples of
16, so the exported graph takes raw linear features of any H, W, plus the exposure of the whole
image (computed by the caller, so that tiles of one image share it: luxest_contract.exposure);
training passes each crop's whole-image exposure (preprocess.py), the inputs the network sees at
inference. Both heads are scale-equivariant through the exposure input: hdr times s with the
exposure over s gives the result times s (denoise's rescaling near the f32 limit relies on it).
Near the autoexposure's 1e-4 floor they are not: callers brighten a dim image first
(luxest_contract.dim_exponent). Growing a model into a larger network is grow.py's."""

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
        e0 = self.enc0(x)  # H
        e1 = self.enc1(F.max_pool2d(e0, 2))  # H/2
        e2 = self.enc2(F.max_pool2d(e1, 2))  # H/4
        e3 = self.enc3(F.max_pool2d(e2, 2))  # H/8
        b = self.bottleneck(F.max_pool2d(e3, 2))  # H/16
        d3 = self.join("dec3", b, e3)  # H/8
        d2 = self.join("dec2", d3, e2)  # H/4
        d1 = self.join("dec1", d2, e1)  # H/2
        d0 = self.join("dec0", d1, e0)  # H
        return [d0, d1, d2, d3, b]

    def join(self, name, coarse, skip):
        """Decoder block `name` over the concatenation of `coarse` upsampled (nearest) and
        `skip`; after `split_joins` as a sum of two convolutions instead (same function)."""
        block = getattr(self, name)
        up = F.interpolate(coarse, scale_factor=2.0, mode="nearest")
        if self.joins is None:
            return block(torch.cat([up, skip], 1))
        conv = block[0][0]
        y = F.conv2d(up, self.joins[name + "_up"], conv.bias, padding=1) + F.conv2d(
            skip, self.joins[name + "_skip"], None, padding=1
        )
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
            term = e[:, i : i + 1] * p[:, :, dy : dy + h, dx : dx + wd]
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
            alpha = torch.sigmoid(pred[:, k2 : k2 + 1])
            low = up(F.avg_pool2d(f, 2))
            if detail_gate:  # beta f + (1 - beta) U(D(f)): exactly f where beta is 1
                beta = torch.sigmoid(pred[:, k2 + 1 : k2 + 2])
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


def denoiser(cfg):
    """The Denoiser of a configuration (config.Config): width, head, features, detail gate."""
    return Denoiser(
        width=cfg.base_width, head=cfg.head, features=cfg.features, detail_gate=cfg.detail_gate, scales=cfg.scales
    )


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
            raise ValueError(
                f"features {', '.join(features)}: expected one of " + "; ".join(", ".join(f) for f in FEATURE_SETS)
            )
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
            self.heads = nn.ModuleList(
                nn.Conv2d(c, head_outputs(s, self.detail_gate, scales), 1)
                for s, c in enumerate(self.unet.channels[:scales])
            )

    def forward(self, x, exposure=None):
        """`exposure` (N,) float: the exposure of each whole image; if None, x must hold whole
        images and it is computed from them (transfer.exposure_of)."""
        h, w = x.shape[2], x.shape[3]
        if exposure is None:
            exposure = transfer.exposure_of(x[:, 0:3]).to(x.device)
        ph, pw = (h + 15) // 16 * 16 - h, (w + 15) // 16 * 16 - w
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
                out = out + x[:, a : a + 3].float().clamp(min=0)
        return out, exp

    def linear(self, out, exp):
        """The output of `transferred` as linear radiance (what the exported model returns)."""
        return transfer.inverse(out, exp) if self.head == "direct" else out

    def loss_domain(self, out, exp):
        """The output of `transferred` in the transferred domain (where the loss is taken)."""
        return out if self.head == "direct" else transfer.forward(out, exp.float())
