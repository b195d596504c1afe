"""The reference of a comparison: the direct render converged, and how noisy it still is.

The reference is the mean of `seeds` renders (`engines.render`) with different seeds, in render units
(the ideal camera's irradiance); its noise is estimated from their differences (σ_ref = RMS(a − b)/2
for two), as one RMS value for the whole image and as a per-pixel variance map for the annuli
(`scores.compare` removes it in quadrature). It is stored as reference.exr with the settings it was
rendered with (`REFERENCE_KEYS`), so that a later run with the same settings can reuse it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import SolasError
from .engines import render

REFERENCE_KEYS = ("lens_hash", "sensor", "fov_deg", "boundary", "spp", "seeds", "response", "fresnel")


@dataclass
class Reference:
    image: np.ndarray  # mean of the renders (H, W, 3) float64
    noise: float  # estimated RMS noise of `image` (absolute)
    spp: int  # total samples per pixel
    seconds: float
    renders: list = field(default_factory=list)  # the individual images

    @property
    def rms(self) -> float:
        """RMS of the image over all pixels and channels."""
        return math.sqrt(float(np.mean(self.image**2)))


def check_reference(spp: int, seeds: int) -> None:
    """SolasError unless `seeds` ≥ 2 renders of spp/seeds samples each can be made."""
    if not (isinstance(seeds, int) and seeds >= 2):
        raise SolasError(
            f"reference seeds {seeds!r} must be an integer >= 2 (the noise is estimated from their spread)"
        )
    if not (isinstance(spp, int) and spp >= seeds):
        raise SolasError(f"reference spp {spp!r} must be an integer >= the number of seeds ({seeds})")


def reference(
    lens,
    image: np.ndarray,
    spp: int,
    fov_deg: float,
    seeds: int = 2,
    boundary: str = "edge",
    variant: str | None = None,
    first_seed: int = 1001,
    progress=None,
) -> Reference:
    """Mean of `seeds` renders of spp/seeds samples each, with its noise estimated from their spread;
    `progress(done, total)` is told the samples per pixel done over all of them."""
    check_reference(spp, seeds)
    per = spp // seeds
    images, seconds = [], 0.0
    for k in range(seeds):
        step = None if progress is None else (lambda done, total, k=k: progress(k * per + done, per * seeds))
        r = render(lens, image, per, first_seed + k, fov_deg, boundary, variant, step)
        images.append(r.image.astype(np.float64))
        seconds += r.seconds
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    # unbiased per-render variance from the spread; the mean's is 1/seeds of it
    var = np.sum((stack - mean) ** 2) / ((seeds - 1) * mean.size)
    return Reference(mean, math.sqrt(var / seeds), per * seeds, seconds, images)


def noise_variance_map(renders: list[np.ndarray]) -> np.ndarray:
    """Per-pixel variance (H, W) of the mean of the renders, averaged over channels (smoothed 9×9:
    an unbiased but less noisy estimate)."""
    from scipy.ndimage import uniform_filter

    stack = np.stack(renders)
    n = len(renders)
    var = ((stack - stack.mean(axis=0)) ** 2).sum(axis=0).mean(axis=-1) / ((n - 1) * n)
    return uniform_filter(var, 9, mode="nearest")


def write_reference(path: Path, ref: Reference, var_map: np.ndarray, meta: dict) -> None:
    """reference.exr: R, G, B and the per-pixel noise variance of the mean ("noise_var"); the metadata
    names what it was rendered with (`REFERENCE_KEYS`), its noise and time, so a later run can reuse it."""
    from ..imageio import image_channels, write_exr

    channels = image_channels(ref.image.astype(np.float32))
    channels["noise_var"] = var_map.astype(np.float32)
    write_exr(
        path,
        channels,
        dict(
            meta,
            spp=ref.spp,
            seeds=len(ref.renders),
            seconds=ref.seconds,
            noise_abs=ref.noise,
            response="lines",
            fresnel="off",
        ),
    )


def read_reference(path: Path, expect: dict) -> tuple[Reference, np.ndarray] | None:
    """The reference stored at `path` if it was rendered with the settings `expect`, else None."""
    from ..imageio import read_exr

    if not path.is_file():
        return None
    channels, meta = read_exr(path)
    if (
        "noise_var" not in channels
        or "noise_abs" not in meta
        or any(meta.get(k) != expect.get(k) for k in REFERENCE_KEYS)
    ):
        return None
    image = np.stack([channels[c] for c in "RGB"], axis=-1).astype(np.float64)
    return Reference(image, float(meta["noise_abs"]), int(meta["spp"]), float(meta["seconds"])), channels[
        "noise_var"
    ].astype(np.float64)
