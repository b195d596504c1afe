"""Cross-validation of the two degradation engines (`solas-mi crossval`): the direct spectral render
through the lens geometry against the PSF-grid convolution, on the same input image and the same camera.

What makes the two comparable (`solas_mi.camera`):

- The render uses the "lines" response (R, G, B = the lens's wavelengths, longest first — the PSF
  grid's channel wavelengths), no Fresnel losses (the tracer's PSFs have none), the same boundary
  rule, and the default camera: the image width spans ±fov_deg and the sensor is the image's grid.
- Units. A render pixel is irradiance in units of the ideal camera's, L·A_EP/f²
  (`illumination.ideal_irradiance`: A_EP = the paraxial entrance-pupil area at the lens's primary
  wavelength, f = the camera's pinhole focal length). The convolution uses PSF grids normalised
  "none" (kernels sum to the beam's transmitted cross-section T(θ) relative to the on-axis paraxial
  entrance pupil at the channel's own wavelength) on the input times cos³θ (the solid angle of a
  texel uniform in tangent space), so its unit is L·A_EP(λ_c)/f²; it is turned into render units by
  k_c = A_EP(λ_c)/A_EP(primary) (0.9965 at 656 nm for the doublet, 1 at 531 nm). With these, a
  uniform white image agrees between the engines to ≈ 0.1 % across the field (distortion, pupil
  aberration and vignetting included).
- Fraunhofer PSFs carry diffraction, which the ray render has not; their tails beyond the PSF window
  are folded back (each PSF rescaled to sum to its T(θ); the captured fraction is recorded), so that
  the comparison measures the shape of the blur and not the window's size.

The reference is the mean of `seeds` renders with different seeds; its noise is estimated from
their differences (σ_ref = RMS(a − b)/2 for two) and each error is also given with the noise removed
in quadrature: e = sqrt(max(0, e_measured² − σ_ref²)).

Errors: relative RMSE = RMS(image − reference)/RMS(reference) over all pixels and channels, and
per annulus (centre < 0.24 R ≤ middle < 0.6 R ≤ edge, R = the half-diagonal, as
`metrics.nssfr`'s automotive annuli); PSNR with data_range = max(reference); SSIM from scikit-image
(channel_axis=-1, same data_range).
"""
from __future__ import annotations

import argparse
import csv
import io
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SolasError
from ..metrics.annuli import ANNULI as SCHEMES
from ..metrics.annuli import ANNULUS_NAMES, annulus_map

ANNULI = SCHEMES["automotive"]  # fractions of the half-diagonal: centre / middle / edge
PSF_KINDS = ("geometric", "fraunhofer")
CONV_METHODS = ("interp", "patch")
# PSF sampling per kind: geometric spots of the doublet fit ±40 µm; Fraunhofer tails need more room
PSF_SAMPLING = {"geometric": (0.5, 160), "fraunhofer": (1.0, 160)}  # (pitch µm, size)
DEFAULT_CASES = ("interp:geometric:32x24", "patch:geometric:32x24", "patch:geometric:8x6",
                 "interp:fraunhofer:32x24", "patch:fraunhofer:32x24", "patch:fraunhofer:8x6")


# ----------------------------------------------------------------------------------------------- input

def load_input(image: str | np.ndarray, sensor: tuple[int, int] | None = None, scale: float | None = None,
               linear: bool = False) -> np.ndarray:
    """The linear H×W×3 float64 input image, resampled (area average) to sensor (rows, columns) or by
    `scale`. PNG/JPEG are sRGB-decoded unless `linear`; a one-channel image is repeated as R, G, B."""
    from ..imageio import read_image

    if isinstance(image, np.ndarray):
        arr = np.asarray(image, dtype=np.float64)
    else:
        arr = read_image(image, linearize=not linear)
    if arr.ndim == 2:
        arr = np.repeat(arr[..., None], 3, axis=-1)
    if arr.ndim != 3 or arr.shape[-1] != 3 or min(arr.shape[:2]) < 8:
        raise SolasError(f"input image of shape {arr.shape} must be H×W (grey) or H×W×3 (RGB), at least 8×8 px")
    if not np.all(np.isfinite(arr)) or arr.min() < 0:
        raise SolasError("input image must hold finite, non-negative linear values")
    if sensor is not None and scale is not None:
        raise SolasError("give either a sensor size or a scale, not both")
    if scale is not None:
        if not (isinstance(scale, (int, float)) and 0 < scale <= 1):
            raise SolasError(f"scale {scale!r} must lie in (0, 1]")
        sensor = (max(8, round(arr.shape[0] * scale)), max(8, round(arr.shape[1] * scale)))
    if sensor is not None and tuple(sensor) != arr.shape[:2]:
        arr = resample(arr, sensor)
    return arr


def resample(arr: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Area-average resampling to (rows, columns): exact block means for integer factors."""
    h, w = arr.shape[:2]
    rows, cols = shape
    if rows > h or cols > w:
        raise SolasError(f"sensor {cols}x{rows} is larger than the image ({w}x{h}); only downscaling is supported")
    if h % rows == 0 and w % cols == 0:
        fy, fx = h // rows, w // cols
        return arr.reshape(rows, fy, cols, fx, arr.shape[2]).mean(axis=(1, 3))
    from skimage.transform import resize

    return resize(arr, (rows, cols, arr.shape[2]), order=1, anti_aliasing=True, preserve_range=True)


def tangent_cos3(width: int, height: int, fov_deg: float) -> np.ndarray:
    """cos³θ (H, W) of each input pixel's direction: (1 + tx² + ty²)^−3/2 with camera.py's tangents."""
    t = math.tan(math.radians(fov_deg)) / (width / 2)
    tx = (np.arange(width) + 0.5 - width / 2) * t
    ty = (height / 2 - np.arange(height) - 0.5) * t
    return (1.0 + tx[None, :] ** 2 + ty[:, None] ** 2) ** -1.5


def render_units(lens, wavelengths_nm, fov_deg: float) -> np.ndarray:
    """k per wavelength: convolution output (input × cos³θ, "none" grid) → render units (the ideal
    camera's irradiance, `illumination.ideal_irradiance`)."""
    from ..optics.camera import pinhole_focal_mm
    from ..optics.illumination import ideal_irradiance

    focal = pinhole_focal_mm(lens, fov_deg)
    unit = ideal_irradiance(lens, focal)
    return np.array([ideal_irradiance(lens, focal, float(w)) / unit for w in wavelengths_nm])


# ------------------------------------------------------------------------------------------ the engines

@dataclass
class Case:
    """One convolution case: method (interp/patch), PSF kind (geometric/fraunhofer), blocks (cols, rows)."""

    method: str
    kind: str
    blocks: tuple[int, int]

    @property
    def name(self) -> str:
        return f"{self.method}:{self.kind}:{self.blocks[0]}x{self.blocks[1]}"

    @classmethod
    def parse(cls, text: str) -> "Case":
        from ..options import parse_wxh

        parts = text.strip().split(":")
        if len(parts) != 3 or parts[0] not in CONV_METHODS or parts[1] not in PSF_KINDS:
            raise SolasError(f"case {text!r} must look like METHOD:PSF:COLSxROWS with METHOD in "
                             f"{'/'.join(CONV_METHODS)} and PSF in {'/'.join(PSF_KINDS)} (e.g. interp:geometric:32x24)")
        rows, cols = parse_wxh(parts[2], "case grid")
        return cls(parts[0], parts[1], (cols, rows))


def psf_grid_for(lens, kind: str, blocks: tuple[int, int], width: int, height: int, fov_deg: float,
                 progress=None):
    """The PSF grid with one node at the centre of each of cols×rows equal blocks of a width×height image
    spanning ±fov_deg (nodes over ±fov × ±fov·H/W: for the doublet's 1280×960 image the paper's 8×8 /
    32×32 grids over ±2° with the rows inside the image), normalised "none"; Fraunhofer PSFs rescaled to
    sum to their transmission. Returns (grid, seconds)."""
    if kind not in PSF_KINDS:
        raise SolasError(f"PSF kind {kind!r} must be one of {', '.join(PSF_KINDS)}")
    from ..psf.grid import psf_grid

    cols, rows = blocks
    pitch, size = PSF_SAMPLING[kind]
    start = time.perf_counter()
    grid = psf_grid(lens, grid=(rows, cols), field_range_deg=(fov_deg, fov_deg * height / width), method=kind,
                         normalization="none", pitch_um=pitch, size=size, progress=progress)
    if kind == "fraunhofer":
        fold_tails(grid)
    return grid, time.perf_counter() - start


def fold_tails(grid) -> None:
    """Rescale each PSF of a "none" grid so that it sums to its transmission (the energy beyond the
    window folded back); records the captured fraction in the metadata."""
    trans = np.asarray(grid.meta["transmission"], dtype=np.float64)
    sums = grid.data.sum(axis=(-2, -1), dtype=np.float64) * grid.pitch_um ** 2
    captured = sums / np.where(trans > 0, trans, 1.0)
    grid.data *= (trans / np.where(sums > 0, sums, 1.0))[..., None, None].astype(np.float32)
    grid.meta["window_captured_fraction"] = {"min": float(captured.min()), "max": float(captured.max()),
                                             "mean": float(captured.mean())}
    grid.meta["tails"] = "each PSF rescaled to sum to its transmission (energy beyond the window folded back)"


def convolve(image: np.ndarray, grid, method: str, lens, fov_deg: float, boundary: str = "edge",
             scale: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """The convolution engine in render units: k_c · degrade(image · cos³θ, grid). Returns (image, seconds)."""
    from ..convolution import degrade
    from ..convolution.kernels import channel_wavelengths

    height, width = image.shape[:2]
    start = time.perf_counter()
    weighted = image * tangent_cos3(width, height, fov_deg)[..., None]
    out = degrade(weighted, grid, method, boundary, dtype=np.float32)
    seconds = time.perf_counter() - start
    if scale is None:
        waves = [grid.wavelengths_nm[k] for k in channel_wavelengths(grid, image.shape[-1])]
        scale = render_units(lens, waves, fov_deg)
    return out * scale.astype(np.float32), seconds


def ideal(image: np.ndarray, lens, fov_deg: float, scale: np.ndarray) -> np.ndarray:
    """The unblurred image in render units (cos³θ and k only): how much the lens changes the image."""
    h, w = image.shape[:2]
    return (image * tangent_cos3(w, h, fov_deg)[..., None] * scale).astype(np.float32)


def render(lens, image: np.ndarray, spp: int, seed: int, fov_deg: float, boundary: str = "edge",
           variant: str | None = None, progress=None):
    """The direct render in the cross-validation's settings (lines, no Fresnel, sensor = image grid)."""
    from ..render.loop import render_image

    h, w = image.shape[:2]
    return render_image(lens, image, sensor=(h, w), spp=spp, response="lines", fov_deg=fov_deg, boundary=boundary,
                        fresnel="off", variant=variant, seed=seed, progress=progress)


@dataclass
class Reference:
    image: np.ndarray  # mean of the renders (H, W, 3) float64
    noise: float  # estimated RMS noise of `image` (absolute)
    spp: int  # total samples per pixel
    seconds: float
    renders: list = field(default_factory=list)  # the individual images


def reference(lens, image: np.ndarray, spp: int, fov_deg: float, seeds: int = 2, boundary: str = "edge",
              variant: str | None = None, first_seed: int = 1001, progress=None) -> Reference:
    """Mean of `seeds` renders of spp/seeds samples each, with its noise estimated from their spread."""
    if not (isinstance(seeds, int) and seeds >= 2):
        raise SolasError(f"reference seeds {seeds!r} must be an integer >= 2 (the noise is estimated from their spread)")
    if not (isinstance(spp, int) and spp >= seeds):
        raise SolasError(f"reference spp {spp!r} must be an integer >= the number of seeds ({seeds})")
    per = spp // seeds
    images, seconds = [], 0.0
    for k in range(seeds):
        r = render(lens, image, per, first_seed + k, fov_deg, boundary, variant, progress)
        images.append(r.image.astype(np.float64))
        seconds += r.seconds
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    # unbiased per-render variance from the spread; the mean's is 1/seeds of it
    var = np.sum((stack - mean) ** 2) / ((seeds - 1) * mean.size)
    return Reference(mean, math.sqrt(var / seeds), per * seeds, seconds, images)


REFERENCE_KEYS = ("lens_hash", "sensor", "fov_deg", "boundary", "spp", "seeds", "response", "fresnel")


def write_reference(path: Path, ref: Reference, var_map: np.ndarray, meta: dict) -> None:
    """reference.exr: R, G, B and the per-pixel noise variance of the mean ("noise_var"); the metadata
    names what it was rendered with (`REFERENCE_KEYS`), its noise and time, so a later run can reuse it."""
    from ..imageio import image_channels, write_exr

    channels = image_channels(ref.image.astype(np.float32))
    channels["noise_var"] = var_map.astype(np.float32)
    write_exr(path, channels, dict(meta, spp=ref.spp, seeds=len(ref.renders), seconds=ref.seconds,
                                   noise_abs=ref.noise, response="lines", fresnel="off"))


def read_reference(path: Path, expect: dict) -> tuple[Reference, np.ndarray] | None:
    """The reference stored at `path` if it was rendered with the settings `expect`, else None."""
    from ..imageio import read_exr

    if not path.is_file():
        return None
    channels, meta = read_exr(path)
    if "noise_var" not in channels or "noise_abs" not in meta or any(
            meta.get(k) != expect.get(k) for k in REFERENCE_KEYS):
        return None
    image = np.stack([channels[c] for c in "RGB"], axis=-1).astype(np.float64)
    return Reference(image, float(meta["noise_abs"]), int(meta["spp"]), float(meta["seconds"])), \
        channels["noise_var"].astype(np.float64)


# ---------------------------------------------------------------------------------------------- metrics

@dataclass
class Errors:
    rel_rmse: float  # RMS(image − ref)/RMS(ref)
    rel_rmse_denoised: float  # reference noise removed in quadrature
    rmse: float
    psnr_db: float
    ssim: float
    annuli: dict[str, float]  # relative RMSE per annulus (normalised by the annulus's RMS(ref))
    annuli_denoised: dict[str, float]


def denoise(err: float, noise: float) -> float:
    return math.sqrt(max(0.0, err * err - noise * noise))


def compare(image: np.ndarray, ref: np.ndarray, ref_noise: float = 0.0, noise_map: np.ndarray | None = None
            ) -> Errors:
    """Errors of `image` against `ref` (same shape). ref_noise: the reference's RMS noise (absolute);
    noise_map: its per-pixel variance estimate (for the annuli; default uniform)."""
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    image = np.asarray(image, dtype=np.float64)
    ref = np.asarray(ref, dtype=np.float64)
    if image.shape != ref.shape:
        raise SolasError(f"image shape {image.shape} differs from the reference's {ref.shape}")
    diff2 = (image - ref) ** 2
    ref_rms = math.sqrt(float(np.mean(ref ** 2)))
    if ref_rms == 0:
        raise SolasError("the reference image is black: nothing to compare against")
    rmse = math.sqrt(float(diff2.mean()))
    top = float(ref.max())
    psnr = float(peak_signal_noise_ratio(ref, image, data_range=top)) if rmse > 0 else float("inf")
    ssim = float(structural_similarity(ref, image, channel_axis=-1, data_range=top))
    rings = annulus_map(*ref.shape[:2])
    var = noise_map if noise_map is not None else np.full(ref.shape[:2], ref_noise ** 2)
    ann, ann_dn = {}, {}
    for i, name in enumerate(ANNULUS_NAMES):
        m = rings == i
        if not m.any():
            continue
        rr = math.sqrt(float(np.mean(ref[m] ** 2)))
        e = math.sqrt(float(diff2[m].mean())) / rr
        ann[name] = e
        ann_dn[name] = denoise(e, math.sqrt(float(np.mean(var[m]))) / rr)
    rel = rmse / ref_rms
    return Errors(rel, denoise(rel, ref_noise / ref_rms), rmse, psnr, ssim, ann, ann_dn)


def noise_variance_map(renders: list[np.ndarray]) -> np.ndarray:
    """Per-pixel variance (H, W) of the mean of the renders, averaged over channels (smoothed 9×9:
    an unbiased but less noisy estimate)."""
    from scipy.ndimage import uniform_filter

    stack = np.stack(renders)
    n = len(renders)
    var = ((stack - stack.mean(axis=0)) ** 2).sum(axis=0).mean(axis=-1) / ((n - 1) * n)
    return uniform_filter(var, 9, mode="nearest")


# --------------------------------------------------------------------------------------------- crossval

@dataclass
class Row:
    """One line of a results table."""

    name: str
    method: str
    psf: str
    grid: str
    psf_seconds: float
    conv_seconds: float
    errors: Errors
    spp: int | None = None

    @property
    def seconds(self) -> float:
        return self.psf_seconds + self.conv_seconds

    def flat(self) -> dict[str, Any]:
        e = self.errors
        out = {"name": self.name, "method": self.method, "psf": self.psf, "grid": self.grid, "spp": self.spp,
               "psf_seconds": round(self.psf_seconds, 3), "run_seconds": round(self.conv_seconds, 3),
               "total_seconds": round(self.seconds, 3),
               "rel_rmse": e.rel_rmse, "rel_rmse_denoised": e.rel_rmse_denoised, "rmse": e.rmse,
               "psnr_db": e.psnr_db, "ssim": e.ssim}
        for k, v in e.annuli.items():
            out[f"rel_rmse_{k}"] = v
        for k, v in e.annuli_denoised.items():
            out[f"rel_rmse_{k}_denoised"] = v
        return out


def markdown_table(rows: list[Row], noise_note: str = "") -> str:
    head = ("| case | PSF | grid | PSF s | run s | total s | rel. RMSE | rel. RMSE − noise | centre | middle | edge "
            "| PSNR dB | SSIM |")
    lines = [head, "|" + "---|" * 13]
    for r in rows:
        e = r.errors
        ann = [e.annuli_denoised.get(n) for n in ANNULUS_NAMES]
        lines.append(
            f"| {r.name} | {r.psf} | {r.grid} | {r.psf_seconds:.2f} | {r.conv_seconds:.2f} | {r.seconds:.2f} | "
            f"{100 * e.rel_rmse:.3f} % | {100 * e.rel_rmse_denoised:.3f} % | "
            + " | ".join("—" if a is None else f"{100 * a:.3f} %" for a in ann)
            + f" | {e.psnr_db:.2f} | {e.ssim:.5f} |")
    if noise_note:
        lines += ["", noise_note]
    return "\n".join(lines) + "\n"


def csv_text(rows: list[Row]) -> str:
    flat = [r.flat() for r in rows]
    keys: list[str] = []
    for f in flat:
        keys += [k for k in f if k not in keys]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=keys, lineterminator="\n")
    w.writeheader()
    w.writerows(flat)
    return buf.getvalue()


def write_rgb_exr(path: Path, image: np.ndarray, meta: dict) -> None:
    from ..imageio import image_channels, write_exr

    write_exr(path, image_channels(np.asarray(image, dtype=np.float32)), meta)


def write_error_map(out: Path, stem: str, image: np.ndarray, ref: np.ndarray, ref_rms: float, meta: dict) -> None:
    """stem_error.exr: signed (image − reference)/RMS(reference) per channel; stem_error.png: its magnitude
    (mean |·| over channels) as a heat map (0 … 5 %) with the annuli drawn."""
    rel = (np.asarray(image, dtype=np.float64) - ref) / ref_rms
    write_rgb_exr(out / f"{stem}_error.exr", rel, dict(meta, values="(image - reference) / RMS(reference)"))
    heat_png(out / f"{stem}_error.png", np.abs(rel).mean(axis=-1), f"{stem}: |image − reference| / RMS(reference)")


def heat_png(path: Path, data: np.ndarray, title: str, vmax: float = 0.05) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle

    from ..imageio import atomic_path

    h, w = data.shape
    fig, ax = plt.subplots(figsize=(8, 8 * h / w + 0.6), dpi=100)
    im = ax.imshow(data, cmap="inferno", vmin=0, vmax=vmax, interpolation="nearest")
    big = math.hypot((w - 1) / 2, (h - 1) / 2)
    for f in ANNULI[:-1]:
        ax.add_patch(Circle(((w - 1) / 2, (h - 1) / 2), f * big, fill=False, color="cyan", lw=0.8, ls="--"))
    ax.set_title(title, fontsize=9)
    ax.set_axis_off()
    fig.colorbar(im, ax=ax, fraction=0.03, pad=0.01, format=lambda v, _: f"{100 * v:.0f} %")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)


@dataclass
class CrossvalResult:
    rows: list[Row]
    reference: Reference
    meta: dict


def crossval(lens, image: np.ndarray, out: str | Path | None, spp: int = 1024, seeds: int = 2,
             cases: tuple[str, ...] = DEFAULT_CASES, fov_deg: float | None = None, boundary: str = "edge",
             variant: str | None = None, baseline: bool = True, reuse: bool = False, log=print) -> CrossvalResult:
    """Degrade `image` (linear H×W×3, the sensor's grid) by the direct render (reference, `spp` in
    `seeds` renders) and by each convolution case; write the error maps and tables to `out` (None:
    write nothing). reuse: take `out`/reference.exr if it was rendered with the same settings."""
    from ..convolution.kernels import check_boundary
    from ..optics.camera import check_fov

    fov = check_fov(lens.field_deg if fov_deg is None else fov_deg)
    check_boundary(boundary)
    parsed = [Case.parse(c) if isinstance(c, str) else c for c in cases]
    if not parsed:
        raise SolasError("no convolution case given")
    h, w = image.shape[:2]
    out_dir = Path(out) if out is not None else None
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
    common = {"lens": lens.name, "lens_hash": lens.hash, "fov_deg": fov, "sensor": [w, h], "boundary": boundary}
    expect = dict(common, spp=spp // seeds * seeds, seeds=seeds, response="lines", fresnel="off")
    stored = read_reference(out_dir / "reference.exr", expect) if reuse and out_dir is not None else None
    if stored is not None:
        ref, var_map = stored
        log(f"crossval: reusing {out_dir / 'reference.exr'} ({ref.spp} spp, rendered in {ref.seconds:.1f} s)")
    else:
        log(f"crossval: {w}x{h} px, reference {spp} spp in {seeds} renders")
        ref = reference(lens, image, spp, fov, seeds, boundary, variant)
        var_map = noise_variance_map(ref.renders)
        if out_dir is not None:
            write_reference(out_dir / "reference.exr", ref, var_map, common)
    ref_rms = math.sqrt(float(np.mean(ref.image ** 2)))
    log(f"crossval: reference noise {100 * ref.noise / ref_rms:.3f} % of RMS")
    grids: dict[tuple[str, tuple[int, int]], tuple[Any, float]] = {}
    rows: list[Row] = []
    scale = None
    for case in parsed:
        key = (case.kind, case.blocks)
        if key not in grids:
            grids[key] = psf_grid_for(lens, case.kind, case.blocks, w, h, fov)
        grid, psf_s = grids[key]
        if scale is None:
            from ..convolution.kernels import channel_wavelengths

            waves = [grid.wavelengths_nm[k] for k in channel_wavelengths(grid, 3)]
            scale = render_units(lens, waves, fov)
        img, conv_s = convolve(image, grid, case.method, lens, fov, boundary, scale)
        err = compare(img, ref.image, ref.noise, var_map)
        blocks = f"{case.blocks[0]}x{case.blocks[1]}"
        rows.append(Row(case.name, case.method, case.kind, blocks, psf_s, conv_s, err))
        log(f"crossval: {case.name}: rel. RMSE {100 * err.rel_rmse:.3f} % ({100 * err.rel_rmse_denoised:.3f} % "
            f"without noise), PSF grid {psf_s:.1f} s, convolution {conv_s:.2f} s")
        if out_dir is not None:
            stem = case.name.replace(":", "_")
            m = dict(common, case=case.name, psf_seconds=psf_s, conv_seconds=conv_s)
            write_rgb_exr(out_dir / f"{stem}.exr", img, m)
            write_error_map(out_dir, stem, img, ref.image, ref_rms, m)
    if baseline:
        err = compare(ideal(image, lens, fov, scale), ref.image, ref.noise, var_map)
        rows.append(Row("ideal (no blur)", "none", "—", "—", 0.0, 0.0, err))
    if ref.renders:  # one of the reference's own renders against the other(s): what the render's noise costs
        half = compare(ref.renders[0], np.mean(ref.renders[1:], axis=0))
        rows.append(Row(f"render {ref.spp // seeds} spp (vs the other seed{'s' if seeds > 2 else ''})", "render",
                        "—", "—", 0.0, ref.seconds / seeds, half, spp=ref.spp // seeds))
    meta = dict(common, reference_spp=ref.spp, reference_seeds=seeds, reference_seconds=ref.seconds,
                reference_noise_rel=ref.noise / ref_rms, render_units_k=[float(k) for k in scale],
                psf_sampling={k: {"pitch_um": p, "size": s} for k, (p, s) in PSF_SAMPLING.items()},
                fraunhofer_window={f"{b[0]}x{b[1]}": g.meta.get("window_captured_fraction")
                                   for (kind, b), (g, _) in grids.items() if kind == "fraunhofer"},
                rows=[r.flat() for r in rows])
    if out_dir is not None:
        from ..imageio import write_text

        note = (f"Reference: mean of {seeds} direct renders, {ref.spp} spp in all ({ref.seconds:.1f} s), noise "
                f"{100 * ref.noise / ref_rms:.3f} % of RMS(reference); \"− noise\" and the annuli remove it in "
                "quadrature. PSF s: computing the PSF grid; run s: the convolution (or render).")
        write_text(out_dir / "table.md", markdown_table(rows, note))
        write_text(out_dir / "table.csv", csv_text(rows))
        write_text(out_dir / "crossval.json", json.dumps(meta, indent=1))
    return CrossvalResult(rows, ref, meta)


# ------------------------------------------------------------------------------------------ command line

def run_crossval(args: argparse.Namespace) -> int:
    from ..optics.lens import Lens
    from ..options import parse_wxh

    lens = Lens.load(args.lens)
    sensor = parse_wxh(args.sensor, "--sensor") if args.sensor else None
    image = load_input(args.image, sensor, args.scale, args.linear)
    cases = tuple(c for c in args.cases.split(",") if c.strip()) if args.cases else DEFAULT_CASES
    res = crossval(lens, image, args.output, args.spp, args.seeds, cases, args.fov_deg, args.boundary,
                   args.variant, reuse=args.reuse_reference, log=lambda s: print(s, flush=True))
    print(markdown_table(res.rows))
    print(f"wrote {args.output}/table.md, table.csv, crossval.json, reference.exr and per case: .exr, _error.exr, "
          "_error.png")
    return 0


def register(sub: Any) -> None:
    """Add the `crossval` subcommand."""
    from ..convolution.kernels import BOUNDARIES
    from ..render.loop import VARIANTS

    p = sub.add_parser(
        "crossval", help="cross-validate the PSF-grid convolution against the direct render",
        description="Degrade one image by the direct spectral render (the reference: lines response, no Fresnel, "
                    "several seeds so that its noise is known) and by each convolution case (interp/patch × "
                    "geometric/Fraunhofer PSFs × grid), in the same units; write the images, per-pixel error "
                    "maps and a table of relative RMSE (whole image and centre/middle/edge annuli), PSNR, SSIM "
                    "and run times (PSF grid and convolution apart).")
    p.add_argument("lens", help="shipped lens name (solas-doublet) or a .toml lens file")
    p.add_argument("image", help="input image, the ideal image spanning ±fov (PNG/JPEG sRGB, EXR linear)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--spp", type=int, default=1024, help="reference samples per pixel, all seeds together "
                                                          "(default 1024; 1280x960 takes ~13 min on 2 cores)")
    p.add_argument("--seeds", type=int, default=2, help="renders the reference is averaged from (>= 2)")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--sensor", help="resample the image to COLSxROWS first (area average); it is the sensor")
    size.add_argument("--scale", type=float, help="resample the image by this factor in (0, 1] first")
    p.add_argument("--cases", help="comma-separated METHOD:PSF:COLSxROWS (default: "
                                   + ",".join(DEFAULT_CASES) + ")")
    p.add_argument("--fov-deg", type=float, help="half the horizontal field the image spans (default: the lens's)")
    p.add_argument("--boundary", choices=BOUNDARIES, default="edge", help="padding / object outside the image")
    p.add_argument("--linear", action="store_true", help="PNG/JPEG values are already linear")
    p.add_argument("--variant", choices=VARIANTS, help="Mitsuba variant of the render")
    p.add_argument("--reuse-reference", action="store_true",
                   help="reuse DIR/reference.exr when it was rendered with the same lens, size, field, boundary, "
                        "spp and seeds (e.g. to add cases without rendering again)")
    p.set_defaults(run=run_crossval)
