"""The two degradation engines in the cross-validation's settings: the direct spectral render through
the lens geometry, and the PSF-grid convolution, on the same input image and the same camera.

What makes the two comparable (`solas_mi.optics.camera`):

- The render uses the "lines" response (R, G, B = the lens's wavelengths, longest first — the PSF
  grid's channel wavelengths), no Fresnel losses (the tracer's PSFs have none), the same boundary
  rule, and the default camera: the image width spans ±fov_deg and the sensor is the image's grid.
- Units. A render pixel is irradiance in units of the ideal camera's, L·A_EP/f²
  (`optics.illumination.ideal_irradiance`: A_EP = the paraxial entrance-pupil area at the lens's primary
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

A convolution case names the convolution method (`convolution.methods.METHODS`), the PSF method
(`psf.methods.METHODS`) and the grid of blocks, e.g. "interp:geometric:32x24"; each PSF method is
sampled as `PSF_SAMPLING` says. Times are wall-clock seconds.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..convolution.kernels import channel_wavelengths
from ..convolution.methods import METHODS as CONVOLUTION_METHODS
from ..convolution.methods import degrade
from ..errors import SolasError
from ..options import parse_wxh
from ..psf.grid import psf_grid
from ..psf.methods import METHODS as PSF_METHODS
from .inputs import tangent_cos3

# PSF sampling per PSF method: geometric spots of the doublet fit ±40 µm; Fraunhofer tails need more room
PSF_SAMPLING = {"geometric": (0.5, 160), "fraunhofer": (1.0, 160)}  # (pitch µm, size)


def render_units(lens, wavelengths_nm, fov_deg: float) -> np.ndarray:
    """k per wavelength: convolution output (input × cos³θ, "none" grid) → render units (the ideal
    camera's irradiance, `optics.illumination.ideal_irradiance`)."""
    from ..optics.camera import pinhole_focal_mm
    from ..optics.illumination import ideal_irradiance

    focal = pinhole_focal_mm(lens, fov_deg)
    unit = ideal_irradiance(lens, focal)
    return np.array([ideal_irradiance(lens, focal, float(w)) / unit for w in wavelengths_nm])


def grid_units(lens, grid, fov_deg: float, channels: int = 3) -> np.ndarray:
    """`render_units` at the wavelengths `grid` gives the channels of a `channels`-channel image."""
    return render_units(lens, [grid.wavelengths_nm[k] for k in channel_wavelengths(grid, channels)], fov_deg)


def check_kind(kind: str) -> str:
    """A PSF method's name (`psf.methods.METHODS`), checked."""
    if kind not in PSF_METHODS:
        raise SolasError(f"PSF kind {kind!r} must be one of {', '.join(PSF_METHODS)}")
    return kind


def parse_blocks(text: str, what: str) -> tuple[int, int]:
    """ "COLSxROWS" → (columns, rows)."""
    rows, cols = parse_wxh(text, what)
    return cols, rows


@dataclass
class Case:
    """One convolution case: method (of `CONVOLUTION_METHODS`), PSF kind (of `PSF_METHODS`), blocks (cols, rows)."""

    method: str
    kind: str
    blocks: tuple[int, int]

    @property
    def name(self) -> str:
        return f"{self.method}:{self.kind}:{self.blocks[0]}x{self.blocks[1]}"

    @classmethod
    def parse(cls, text: str) -> Case:
        parts = text.strip().split(":")
        if len(parts) != 3 or parts[0] not in CONVOLUTION_METHODS or parts[1] not in PSF_METHODS:
            raise SolasError(
                f"case {text!r} must look like METHOD:PSF:COLSxROWS with METHOD in "
                f"{'/'.join(CONVOLUTION_METHODS)} and PSF in {'/'.join(PSF_METHODS)} "
                "(e.g. interp:geometric:32x24)"
            )
        return cls(parts[0], parts[1], parse_blocks(parts[2], "case grid"))


def psf_grid_for(lens, kind: str, blocks: tuple[int, int], width: int, height: int, fov_deg: float, progress=None):
    """The PSF grid with one node at the centre of each of cols×rows equal blocks of a width×height image
    spanning ±fov_deg (nodes over ±fov × ±fov·H/W: for the doublet's 1280×960 image the paper's 8×8 /
    32×32 grids over ±2° with the rows inside the image), normalised "none"; Fraunhofer PSFs rescaled to
    sum to their transmission. Returns (grid, seconds)."""
    check_kind(kind)
    cols, rows = blocks
    pitch, size = PSF_SAMPLING[kind]
    start = time.perf_counter()
    grid = psf_grid(
        lens,
        grid=(rows, cols),
        field_range_deg=(fov_deg, fov_deg * height / width),
        method=kind,
        normalization="none",
        pitch_um=pitch,
        size=size,
        progress=progress,
    )
    if kind == "fraunhofer":
        fold_tails(grid)
    return grid, time.perf_counter() - start


def fold_tails(grid) -> None:
    """Rescale each PSF of a "none" grid so that it sums to its transmission (the energy beyond the
    window folded back); records the captured fraction in the metadata."""
    trans = np.asarray(grid.meta["transmission"], dtype=np.float64)
    sums = grid.data.sum(axis=(-2, -1), dtype=np.float64) * grid.pitch_um**2
    captured = sums / np.where(trans > 0, trans, 1.0)
    grid.data *= (trans / np.where(sums > 0, sums, 1.0))[..., None, None].astype(np.float32)
    grid.meta["window_captured_fraction"] = {
        "min": float(captured.min()),
        "max": float(captured.max()),
        "mean": float(captured.mean()),
    }
    grid.meta["tails"] = "each PSF rescaled to sum to its transmission (energy beyond the window folded back)"


def convolve(
    image: np.ndarray, grid, method: str, lens, fov_deg: float, boundary: str = "edge", scale: np.ndarray | None = None
) -> tuple[np.ndarray, float]:
    """The convolution engine in render units: k_c · degrade(image · cos³θ, grid). Returns (image, seconds)."""
    height, width = image.shape[:2]
    start = time.perf_counter()
    weighted = image * tangent_cos3(width, height, fov_deg)[..., None]
    out = degrade(weighted, grid, method, boundary, dtype=np.float32)
    seconds = time.perf_counter() - start
    if scale is None:
        scale = grid_units(lens, grid, fov_deg, image.shape[-1])
    return out * scale.astype(np.float32), seconds


def ideal(image: np.ndarray, fov_deg: float, scale: np.ndarray) -> np.ndarray:
    """The unblurred image in render units (cos³θ and k only): how much the lens changes the image."""
    h, w = image.shape[:2]
    return (image * tangent_cos3(w, h, fov_deg)[..., None] * scale).astype(np.float32)


def render(
    lens,
    image: np.ndarray,
    spp: int,
    seed: int,
    fov_deg: float,
    boundary: str = "edge",
    variant: str | None = None,
    progress=None,
):
    """The direct render in the cross-validation's settings (lines, no Fresnel, sensor = image grid)."""
    from ..render.image import render_image

    h, w = image.shape[:2]
    return render_image(
        lens,
        image,
        sensor=(h, w),
        spp=spp,
        response="lines",
        fov_deg=fov_deg,
        boundary=boundary,
        fresnel="off",
        variant=variant,
        seed=seed,
        progress=progress,
    )
