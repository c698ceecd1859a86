"""An OIDN-style U-Net: 4 levels of 3x3 convolutions + ReLU with max-pool down and nearest
up-sampling and skip connections, on the transferred hdr + albedo + normal (9 channels).

`Denoiser` wraps it with the contract of transfer.py and the padding to multiples of 16, so the
exported graph takes raw linear features of any H, W, plus the image's exposure (computed by the
caller over the whole image, so that tiles of one image share it: luxest_contract.exposure).
Training passes the stored whole-image exposure of each crop's image (preprocess.py), so the
network is trained on exactly the inputs it sees at inference."""
import torch
import torch.nn as nn
import torch.nn.functional as F

import transfer


def conv(cin, cout):
    return nn.Sequential(nn.Conv2d(cin, cout, 3, padding=1), nn.ReLU(inplace=True))


class UNet(nn.Module):
    def __init__(self, in_channels=9, out_channels=3, width=24):
        super().__init__()
        c1, c2, c3, c4, c5 = width, width * 3 // 2, width * 2, width * 5 // 2, width * 3
        self.enc0 = nn.Sequential(conv(in_channels, c1), conv(c1, c1))
        self.enc1 = conv(c1, c2)
        self.enc2 = conv(c2, c3)
        self.enc3 = conv(c3, c4)
        self.bottleneck = conv(c4, c5)
        self.dec3 = nn.Sequential(conv(c5 + c4, c4), conv(c4, c4))
        self.dec2 = nn.Sequential(conv(c4 + c3, c3), conv(c3, c3))
        self.dec1 = nn.Sequential(conv(c3 + c2, c2), conv(c2, c2))
        self.dec0 = nn.Sequential(conv(c2 + c1, c1), conv(c1, c1))
        self.out = nn.Conv2d(c1, out_channels, 3, padding=1)

    def forward(self, x):
        e0 = self.enc0(x)                      # H
        e1 = self.enc1(F.max_pool2d(e0, 2))    # H/2
        e2 = self.enc2(F.max_pool2d(e1, 2))    # H/4
        e3 = self.enc3(F.max_pool2d(e2, 2))    # H/8
        b = self.bottleneck(F.max_pool2d(e3, 2))  # H/16
        up = lambda t: F.interpolate(t, scale_factor=2.0, mode="nearest")
        d3 = self.dec3(torch.cat([up(b), e3], 1))    # H/8
        d2 = self.dec2(torch.cat([up(d3), e2], 1))   # H/4
        d1 = self.dec1(torch.cat([up(d2), e1], 1))   # H/2
        d0 = self.dec0(torch.cat([up(d1), e0], 1))   # H
        return self.out(d0)


class Denoiser(nn.Module):
    """Raw linear (N, 9, H, W) hdr+alb+nrm -> linear (N, 3, H, W) radiance."""

    def __init__(self, width=24):
        super().__init__()
        self.unet = UNet(width=width)

    def forward(self, x, exposure=None):
        """`exposure` (N,) float: the exposure of each whole image; if None, x must hold whole
        images and it is computed from them (transfer.exposure_of)."""
        h, w = x.shape[2], x.shape[3]
        hdr = x[:, 0:3]
        if exposure is None:
            exposure = transfer.exposure_of(hdr).to(x.device)
        exp = exposure.view(-1, 1, 1, 1)
        inp = torch.cat([transfer.forward(hdr, exp), x[:, 3:9]], 1)
        ph, pw = (16 - h % 16) % 16, (16 - w % 16) % 16
        inp = F.pad(inp, (0, pw, 0, ph), mode="replicate")
        out = self.unet(inp)[:, :, :h, :w]
        return transfer.inverse(out, exp)

    def transferred(self, x, exposure):
        """The network output in the transferred domain (for the loss), and the exposure as
        (N, 1, 1, 1). `exposure` (N,): that of each crop's whole image (never the crop's own)."""
        hdr = x[:, 0:3]
        exp = exposure.view(-1, 1, 1, 1).to(x.dtype)
        inp = torch.cat([transfer.forward(hdr, exp), x[:, 3:9]], 1)
        return self.unet(inp), exp
