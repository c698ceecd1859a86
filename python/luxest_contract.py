"""The contracts between luxest's stages, for Python: file naming, EXR header keys and estimator
names, the denoiser model's ONNX tensor names, EXR I/O and the autoexposure. The one Python place
for each (docs/architecture.md, *Contracts*).

Rust has the same in `luxest-io` (`naming`, `header`, `exr`, `exposure`) and crates/denoise
(`model::tensor`); the two are tied by the fixtures in `tests/fixtures/contract/`, which Rust
writes and `training/tests/test_contract.py` reads: every name composed and parsed alike, a
ZIP-compressed Rust EXR read to the header values Rust wrote, the same estimator and tensor
names, Python's exposure equal to Rust's.

Naming (the Intel Open Image Denoise training-toolkit layout):
    <name>_<spp, 6 digits>spp.<kind>.exr     a noisy image at spp samples per pixel
    <name>_ref.<kind>.exr                     the reference
    <name>_<paths, 6 digits>le.<kind>.exr     a double-local-estimate image of `paths` light paths
kind: hdr (radiance), alb (albedo), nrm (normal), z (depth), emi (emitted radiance seen directly,
the image's own samples), ema (the same, antialiased: at least aov-write's --min-samples),
se (standard error), dn (denoised).
Counts have at least 6 digits; a name that does not follow the layout parses to None, as in Rust.

Images are OpenEXR scanline files, 32-bit float R, G, B, ZIP-compressed, read and written with
PyPI `openexr`; run metadata are string attributes under the keys below."""

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

# --- File naming -------------------------------------------------------------------------------

FEATURES = ("hdr", "alb", "nrm", "emi", "ema")
"""The denoiser's input features, in the order of the model's input channels: a model takes the
first three, four or all five (its `luxest.channels` metadata says which; luxest-io's denoise
reads the same)."""

RADIANCE_FEATURES = ("hdr", "emi", "ema")
"""The features that are radiance (scaled with hdr by `dim_exponent`; crates/denoise
`Feature::is_radiance`); the others are properties of the surface."""

KINDS = ("hdr", "alb", "nrm", "z", "emi", "ema", "se", "dn")
"""Every image kind (luxest-io `naming::Kind`)."""

_NAME = re.compile(r"^(?P<name>.+)_(?:(?P<count>\d{6,})(?P<unit>spp|le)|(?P<ref>ref))\.(?P<kind>[a-z]+)\.exr$")


@dataclass(frozen=True)
class ImageName:
    """A parsed image file name. `spp` is None for the reference; for a double-local-estimate
    image (`le`) it is the number of light paths."""

    name: str
    spp: object  # int or None
    reference: bool
    kind: str
    unit: str = "spp"  # "spp" or "le"

    @property
    def file(self):
        return image_name(self.name, self.kind, None if self.reference else self.spp, unit=self.unit)


OWN_FEATURES_DIR = "own"
"""The directory, inside a split's, of the feature images of its scenes' noisy levels below
FEATURE_SPP at the level's own sample count (aov-write --min-samples 1, seed NOISY_SEED):
`<split>/own/<name>_<count>spp.{alb,nrm,emi,ema}.exr`, paired with the split's own radiance
`<split>/<name>_<count>spp.hdr.exr` (the same samples) and reference (make noisy;
pipelines/naming.mk lx_own). The split's own features are antialiased (--min-samples
FEATURE_SPP); training draws one of the two sets per crop."""

REALIZATION_DIR = "seed{seed}"
"""The directory, inside a split's, of an extra noise realization of its scenes' noisy levels:
`<split>/seed<k>/<name>_<count>spp.<kind>.exr`, rendered with seed k (make noisy's
NOISY_EXTRA_SEEDS; pipelines/naming.mk lx_realization), paired with `<split>/<name>_ref`."""


def count_tag(count, unit="spp"):
    """`000064spp` (or `001000le`): a sample or path count zero-padded to 6 digits."""
    if unit not in ("spp", "le"):
        raise ValueError(f"unknown count unit {unit!r}")
    if int(count) != count or count < 0:
        raise ValueError(f"sample count {count!r} is not a non-negative integer")
    return f"{int(count):06d}{unit}"


def image_name(name, kind, spp=None, unit="spp"):
    """The file name of image `kind` of `name` at `spp` samples (None: the reference)."""
    if kind not in KINDS:
        raise ValueError(f"unknown image kind {kind!r} (one of {', '.join(KINDS)})")
    tag = "ref" if spp is None else count_tag(spp, unit)
    return f"{name}_{tag}.{kind}.exr"


def parse_image_name(filename):
    """The `ImageName` of a file name (a path's last component), or None if it is not one."""
    m = _NAME.match(Path(filename).name)
    if not m or m.group("kind") not in KINDS:
        return None
    if m.group("ref"):
        return ImageName(m.group("name"), None, True, m.group("kind"))
    return ImageName(m.group("name"), int(m.group("count")), False, m.group("kind"), m.group("unit"))


def scan(directory, unit="spp"):
    """{name: {count or None: {kind: path}}} of the images of one unit in a directory: the
    camera estimates (`spp`, with the references under None) or the local-estimate images (`le`,
    keyed by light paths)."""
    out = {}
    for p in sorted(Path(directory).glob("*.exr")):
        n = parse_image_name(p.name)
        if n and n.unit == unit:
            out.setdefault(n.name, {}).setdefault(n.spp, {})[n.kind] = p
    return out


# --- Header keys (the same names as luxest-io's `header` module) -------------------------------

SAMPLES = "luxest.samples"  # samples per pixel, or light paths (integer)
SEED = "luxest.seed"  # the seed of all random numbers of the run (integer)
SECONDS = "luxest.seconds"  # wall-clock render seconds, excluding I/O (float)
ESTIMATOR = "luxest.estimator"  # path-tracing, first-hit-features, double-local-estimate, ...
SCENE_HASH = "luxest.sceneHash"  # content hash of the compiled scene
VERSION = "luxest.version"  # version of the program that wrote the file
PIXEL_FILTER = "luxest.pixelFilter"  # pixel reconstruction filter of camera estimators (box)
SINGULARITY = "luxest.singularity"  # the double local estimate's singularity handling
PIXEL_SAMPLES = "luxest.pixelSamples"  # camera samples per pixel of the double local estimate
DENOISER = "luxest.denoiser"  # what denoised the image: a luxest model's file name, or
OIDN_DENOISER_PREFIX = "oidn-"  # ... this prefix and the version for Intel Open Image Denoise
DENOISE_SECONDS = "luxest.denoiseSeconds"  # wall-clock seconds of denoising inference
DENOISE_CPU_SECONDS = "luxest.denoiseCpuSeconds"  # its CPU seconds: the process's user + system, all threads
FEATURE_SECONDS = "luxest.featureSeconds"  # render seconds of the feature images a denoising used
CHANNELS = "luxest.channels"  # ONNX metadata: input features in order (hdr,alb,nrm)
MODEL_TRANSFER = "luxest.transfer"  # ONNX metadata: the transfer function and exposure input
MODEL_PADDING = "luxest.padding"  # ONNX metadata: how H and W are padded
MODEL_CONFIG = "luxest.config"  # ONNX metadata: the training configuration (JSON)
MODEL_METRICS = "luxest.metrics"  # ONNX metadata: scores on the held-out scenes (JSON)
# ONNX metadata: the least samples per pixel of the albedo and normal features the model was
# trained for (aov-write --min-samples); 1: features of any count, antialiased or the image's own.
# denoise refuses features of fewer (an image of at least that many samples always passes).
FEATURE_SAMPLES = "luxest.feature_samples"
# ONNX metadata: the mean luminance the model's input radiance is scaled into by a power of two,
# [v, 2 v) (range_exponent); absent: only dim images are brightened (dim_exponent).
MEAN_LUMINANCE = "luxest.mean_luminance"
EXPOSURE = "luxest.exposure"  # preprocessed data: the whole image's autoexposure

KEYS = (
    SAMPLES,
    SEED,
    SECONDS,
    ESTIMATOR,
    SCENE_HASH,
    VERSION,
    PIXEL_FILTER,
    SINGULARITY,
    PIXEL_SAMPLES,
    DENOISER,
    DENOISE_SECONDS,
    DENOISE_CPU_SECONDS,
    FEATURE_SECONDS,
    CHANNELS,
)
"""The keys of Rust's header module, in its order. (EXPOSURE is Python's: preprocessing only.)"""

TYPES = {
    SAMPLES: int,
    SEED: int,
    SECONDS: float,
    PIXEL_SAMPLES: int,
    DENOISE_SECONDS: float,
    DENOISE_CPU_SECONDS: float,
    FEATURE_SECONDS: float,
}
"""Keys whose values are numbers; every other key is text."""


# --- Estimator names: the values of ESTIMATOR (luxest-io's `header::estimator`) -----------------

PATH_TRACING = "path-tracing"  # trace
FIRST_HIT_FEATURES = "first-hit-features"  # aov-write
LOCAL_ESTIMATE = "local-estimate"  # estimate sensors
DIRECT_SIMULATION = "direct-simulation"  # estimate direct
GATHER = "gather"  # estimate gather
DOUBLE_LOCAL_ESTIMATE = "double-local-estimate"  # estimate image
LIGHT_TRACING = "light-tracing"  # estimate image --light-tracing

ESTIMATORS = (
    PATH_TRACING,
    FIRST_HIT_FEATURES,
    LOCAL_ESTIMATE,
    DIRECT_SIMULATION,
    GATHER,
    DOUBLE_LOCAL_ESTIMATE,
    LIGHT_TRACING,
)
"""Every estimator name, in the order of Rust's `header::estimator::ALL`."""

DENOISED_SUFFIX = "+denoise"  # evaluate's label of an image a luxest model denoised: <estimator>+denoise
OIDN_SUFFIX = "+oidn"  # ... and of one Intel Open Image Denoise 1.x denoised: <estimator>+oidn
OIDN2_SUFFIX = "+oidn2"  # ... and of one OIDN 2.x denoised (the peer of make eval): <estimator>+oidn2


def estimator_label(estimator, denoiser=None):
    """How `evaluate images` labels an image of `estimator` denoised by `denoiser` (its
    `luxest.denoiser`, None if not denoised): evaluate's `images::estimator_label` (`+oidn` for
    OIDN 1.x, `+oidn<major>` for a later release)."""
    if denoiser is None:
        return estimator
    if not denoiser.startswith(OIDN_DENOISER_PREFIX):
        return estimator + DENOISED_SUFFIX
    major = denoiser[len(OIDN_DENOISER_PREFIX) :].split(".")[0]
    return estimator + OIDN_SUFFIX + (major if major not in ("", "1") else "")


class ContractError(ValueError):
    """Bad input: the message is one line naming the file and the problem."""


def header_value(header, key, path="<header>", required=False):
    """The typed value of `key` in a header dict (int, float or str per TYPES), None if absent
    (an error if `required`), a ContractError naming `path` if malformed."""
    raw = header.get(key)
    if raw is None:
        if required:
            raise ContractError(f"{path}: missing header attribute {key}")
        return None
    if isinstance(raw, bytes):
        raw = raw.decode()
    typ = TYPES.get(key, str)
    try:
        return typ(str(raw).strip()) if typ is not str else str(raw)
    except ValueError:
        raise ContractError(f"{path}: header attribute {key} = `{raw}` is not a valid {typ.__name__}") from None


def samples(header, path="<header>"):
    """Samples per pixel (or light paths) of an image header; required."""
    return header_value(header, SAMPLES, path, required=True)


def seed(header, path="<header>"):
    """The seed of an image header; required."""
    return header_value(header, SEED, path, required=True)


# --- The denoiser model's ONNX graph (crates/denoise `model::tensor`) -------------------------

INPUT_TENSOR = "input"  # float32 (N, 3 x features, H, W): the raw linear features of CHANNELS
EXPOSURE_TENSOR = "exposure"  # float32 (N,): the autoexposure of each whole image (`exposure`)
OUTPUT_TENSOR = "output"  # float32 (N, 3, H, W): the denoised linear radiance

TENSORS = (INPUT_TENSOR, EXPOSURE_TENSOR, OUTPUT_TENSOR)
"""The graph's tensor names: its inputs, then its output (Rust's `model::tensor::ALL`)."""


# --- EXR I/O -----------------------------------------------------------------------------------


@dataclass
class Image:
    """An RGB image (H, W, 3) float32 and its `luxest.*` (and other string) header attributes."""

    pixels: np.ndarray
    header: dict
    path: str = "<memory>"

    def value(self, key, required=False):
        return header_value(self.header, key, self.path, required)


def read(path):
    """The `Image` of an EXR file: R, G, B as float32 (H, W, 3), string attributes as text.
    ContractError naming the file if it is not an RGB float EXR."""
    import OpenEXR

    path = str(path)
    try:
        with OpenEXR.File(path) as f:
            # Copied inside the block: the header is the open file's and is emptied on close.
            header = {
                k: (v.decode() if isinstance(v, bytes) else v)
                for k, v in f.header().items()
                if isinstance(v, (str, bytes))
            }
            channels = f.channels()
            if "RGB" in channels:
                px = np.asarray(channels["RGB"].pixels)
            elif all(c in channels for c in "RGB"):
                px = np.stack([np.asarray(channels[c].pixels) for c in "RGB"], axis=-1)
            else:
                raise ContractError(f"{path}: expected channels R, G, B; found {', '.join(sorted(channels))}")
    except ContractError:
        raise
    except Exception as e:  # openexr raises RuntimeError / OSError with multi-line text
        msg = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise ContractError(f"{path}: not a readable OpenEXR file ({msg})") from None
    if px.dtype != np.float32:
        raise ContractError(f"{path}: channels are {px.dtype}, expected 32-bit float")
    return Image(np.ascontiguousarray(px), header, path)


def read_rgb(path):
    """The pixels of an EXR file as float32 (H, W, 3)."""
    return read(path).pixels


def read_header(path):
    """The string attributes of an EXR file (the pixels are read too; files are small)."""
    return read(path).header


def write(path, pixels, header=None):
    """Writes (H, W, 3) pixels as a ZIP-compressed float32 RGB EXR with `header`'s string
    attributes (values converted with str), atomically (a temporary name, then renamed)."""
    import OpenEXR

    px = np.ascontiguousarray(pixels, dtype=np.float32)
    if px.ndim != 3 or px.shape[2] != 3:
        raise ContractError(f"{path}: pixels of shape {px.shape}, expected (H, W, 3)")
    h = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for k, v in (header or {}).items():
        h[k] = str(v)
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    with OpenEXR.File(h, {"RGB": px}) as f:
        f.write(str(tmp))
    tmp.replace(path)


# --- Exposure ----------------------------------------------------------------------------------

EXPOSURE_KEY_VALUE = 0.18  # middle grey (Reinhard et al. 2002, "Photographic Tone Reproduction")
EXPOSURE_EPS = 1e-4  # keeps ln finite on black pixels
LUMA = (0.2126, 0.7152, 0.0722)  # Rec. 709 / sRGB luminance weights (ITU-R BT.709-6)


def luminance(rgb):
    """The Rec. 709 luminance Y of (..., 3) pixels, in float64 (the Y of `exposure`)."""
    a = np.asarray(rgb)
    return (
        a[..., 0].astype(np.float64) * LUMA[0]
        + a[..., 1].astype(np.float64) * LUMA[1]
        + a[..., 2].astype(np.float64) * LUMA[2]
    )


def exposure(hdr, scale=1.0):
    """The autoexposure of a whole image (..., 3): 0.18 / exp(mean ln(max(Y, 0) + 1e-4)), Y the
    Rec. 709 luminance, accumulated in float64 — exactly `RgbImage::autoexposure` in luxest-io.
    Used by the denoiser's input transfer and by the evaluation tonemap; 1.0 for an empty image.
    With `scale`, that of the image times `scale` (each Y times it, `autoexposure_scaled`)."""
    a = np.asarray(hdr)
    if a.size == 0:
        return 1.0
    y = luminance(a) * scale
    return EXPOSURE_KEY_VALUE / math.exp(float(np.log(np.maximum(y, 0.0) + EXPOSURE_EPS).mean()))


DIM_LUMINANCE = 1.0 / 32.0
"""The mean luminance below which a denoiser brightens its input (luxest-io `DIM_LUMINANCE`)."""


def filtered_luminance(hdr, emi=None):
    """The mean over pixels of the Rec. 709 luminance of max(hdr - emi, 0) (per channel, float64;
    max(hdr, 0) without `emi`): the radiance a model with the `emi` feature denoises, the mean
    that dim_exponent and range_exponent bring into range (luxest-io `filtered_luminance`)."""
    a = np.asarray(hdr, dtype=np.float64)
    if a.size == 0:
        return 0.0
    a = np.maximum(a - np.asarray(emi, dtype=np.float64), 0.0) if emi is not None else np.maximum(a, 0.0)
    return float(luminance(a).mean())


def range_exponent(hdr, emi=None, low=None):
    """The power of two e by which a denoiser multiplies the radiance features it gives a model
    that records `low` in its metadata MEAN_LUMINANCE: the e (negative for a bright image) with
    low <= 2**e L < 2 low, L = filtered_luminance(hdr, emi), so that images differing by a power
    of two give the model the same input, bright or dim; 0 for a black image. Without `low`,
    dim_exponent (models without the key). Exactly luxest-io's `range_exponent`."""
    if low is None:
        return dim_exponent(hdr, emi)
    mean = filtered_luminance(hdr, emi)
    if not mean > 0.0 or not math.isfinite(mean):
        return 0
    e = 0
    while mean * 2.0**e < low:
        e += 1
    while mean * 2.0**e >= 2.0 * low:
        e -= 1
    return e


def model_mean_luminance(metadata):
    """The MEAN_LUMINANCE of a model's metadata map as a float, or None when absent."""
    v = metadata.get(MEAN_LUMINANCE)
    return None if v is None else float(v)


def dim_exponent(hdr, emi=None):
    """The power of two e by which a denoiser multiplies the radiance features it gives a model
    (with the exposure of the brightened hdr, `exposure(hdr, 2**e)`; the output is divided by
    2**e): the least e >= 0 with 2**e L >= DIM_LUMINANCE, L the mean luminance of max(hdr - emi,
    0) (per channel, float64; max(hdr, 0) without `emi`); 0 for a black or not dim image. Exactly
    luxest-io's `dim_exponent` (the autoexposure's 1e-4 would otherwise make a model's input
    depend on the radiance's unit; docs/architecture.md, *Exposure and tonemap*)."""
    mean = filtered_luminance(hdr, emi)
    if not mean > 0.0 or mean >= DIM_LUMINANCE:
        return 0
    e = 0  # the least e with mean 2**e >= DIM_LUMINANCE
    while mean * 2.0**e < DIM_LUMINANCE:
        e += 1
    return e


def evaluation_exposure(ref):
    """The exposure of the evaluation tonemap for reference `ref` (evaluate's
    `metrics::autoexposure`): `exposure(ref)`, or for a dim reference 2**e exposure(ref, 2**e)
    with e = dim_exponent(ref), so that metrics do not depend on the radiance's unit."""
    s = 2.0 ** dim_exponent(ref)
    return s * exposure(ref, s)


# --- Sensor results ----------------------------------------------------------------------------

SENSORS_SUFFIX = ".sensors.ron"
"""Sensor results are `<name>.sensors.ron` (+ `.sensors.csv` with one row per point:
set, index, x, y, z, nx, ny, nz, value_<unit>, standard_error_<unit>, r, g, b)."""


def sensors_name(directory, name):
    """`<directory>/<name>.sensors.ron`."""
    return Path(directory) / f"{name}{SENSORS_SUFFIX}"


def read_sensor_run(path):
    """The run metadata of a sensor-results RON file — `run: (samples, seed, seconds,
    estimator, ...)` — as {field: int, float or str}; ContractError naming the file if absent."""
    text = Path(path).read_text()
    m = re.search(r"\brun\s*:\s*(?:RunInfo)?\s*\(([^()]*)\)", text)
    if not m:
        raise ContractError(f"{path}: no run metadata (`run: (...)`) in the sensor results")
    out = {}
    for key, value in re.findall(r"(\w+)\s*:\s*(\"[^\"]*\"|[^,\s]+)", m.group(1)):
        if value.startswith('"'):
            out[key] = value[1:-1]
        else:
            try:
                out[key] = int(value)
            except ValueError:
                out[key] = float(value)
    for key in ("samples", "seed", "seconds"):
        if key not in out:
            raise ContractError(f"{path}: run metadata lacks `{key}`")
    return out


def _read_csv(path):
    import csv

    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        raise ContractError(f"{path}: {e.strerror}") from None
    if not rows:
        raise ContractError(f"{path}: no rows")
    return rows


def _unit(path, row, prefix):
    """The unit of a `<prefix><unit>` column (value_lx -> lx)."""
    for k in row:
        if k.startswith(prefix):
            return k[len(prefix) :]
    raise ContractError(f"{path}: no {prefix}<unit> column")


def _floats(path, rows, keys):
    for r in rows:
        for k in keys:
            try:
                r[k] = float(r[k]) if r.get(k) not in (None, "") else math.nan
            except ValueError:
                raise ContractError(f"{path}: column {k} = `{r[k]}` is not a number") from None
    return rows


def read_sensors_csv(path):
    """The CSV copy of sensor results: rows with `set`, `index`, `value`, `standard_error` (floats,
    whatever the unit) and the rest as written; and the unit."""
    rows = _read_csv(path)
    unit = _unit(path, rows[0], "value_")
    for r in rows:
        r["value"], r["standard_error"] = r[f"value_{unit}"], r[f"standard_error_{unit}"]
    return _floats(path, rows, ("value", "standard_error")), unit


IMAGE_REPORT_NUMBERS = (
    "samples",
    "render_seconds",
    "feature_seconds",
    "denoise_seconds",
    "total_seconds",
    "psnr_db",
    "ssim",
    "ms_ssim",
    "flip",
    "rel_mse",
    "smape",
)
"""The numeric columns of `evaluate images`' CSV report (one row per test image)."""


def read_image_report(path):
    """`evaluate images`' CSV report: one dict per test image, numbers as floats (NaN if empty)."""
    return _floats(path, _read_csv(path), IMAGE_REPORT_NUMBERS)


def read_sensor_report(path):
    """`evaluate sensors`' CSV report: rows with `results`, `case`, `point` and floats `exact`,
    `estimate`, `standard_error` (whatever the unit), `z`, `relative_error`; and the unit."""
    rows = _read_csv(path)
    unit = _unit(path, rows[0], "exact_")
    for r in rows:
        r["exact"], r["estimate"], r["standard_error"] = (
            r[f"exact_{unit}"],
            r[f"estimate_{unit}"],
            r[f"standard_error_{unit}"],
        )
    return _floats(path, rows, ("exact", "estimate", "standard_error", "z", "relative_error")), unit
