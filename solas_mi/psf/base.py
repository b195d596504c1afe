"""What every PSF shares, whatever computed it: the `PSF` record, the grid and value conventions,
the checks of sampling arguments and the metadata. Imports no method (`methods` is the registry).

Grid convention: `size`×`size` pixels of `pitch_um`; the chief ray's image point is at pixel
(size//2, size//2); row 0 is the top (largest y), column 0 the left (smallest x). Values are
irradiance per µm² as a fraction of the on-axis entrance-pupil power ("none"), or normalised to unit
sum ("sum", default) or unit peak ("peak").
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..cores import cores, threads
from ..errors import SolasError
from ..optics import notes

NORMALIZATIONS = ("sum", "peak", "none")
VALUE_MEANING = {
    "sum": "unit sum over the grid",
    "peak": "unit peak",
    "none": "irradiance per um^2 as a fraction of the on-axis entrance-pupil power",
}
DEFAULT_PITCH_UM = 0.5
DEFAULT_SIZE = 160


@dataclass
class PSF:
    """One PSF and what it means, as `psf` computes it.

    The grid convention is this module's: pixel (size//2, size//2) on the chief ray, row 0 the top.

    Parameters
    ----------
    data : numpy.ndarray
        (size, size) values in image orientation, as `normalization` says.
    pitch_um : float
        The pixel pitch on the image plane (µm).
    field_deg : (float, float)
        The field, (x, y) degrees.
    wavelengths_nm : tuple of float
        The wavelengths (nm) summed.
    weights : tuple of float
        Their power weights, summing to 1.
    chief_ray_mm : (float, float)
        The image-plane point (mm) at pixel (size//2, size//2): the first wavelength's chief ray.
    method : str
        The PSF method, a name of `registry.METHODS`.
    normalization : str
        One of `NORMALIZATIONS`: "sum" (unit sum), "peak" (unit peak) or "none" (irradiance per µm² as
        a fraction of the on-axis entrance-pupil power).
    meta : dict, optional
        What else describes it: the lens, the method's options, the transmission, the window's share of
        the light ("energy_in_grid"), warnings.
    """

    data: np.ndarray
    pitch_um: float
    field_deg: tuple[float, float]
    wavelengths_nm: tuple[float, ...]
    weights: tuple[float, ...]
    chief_ray_mm: tuple[float, float]
    method: str
    normalization: str
    meta: dict = field(default_factory=dict)

    @property
    def size(self) -> int:
        """Pixels per side."""
        return self.data.shape[0]

    @property
    def x_um(self) -> np.ndarray:
        """Column centres relative to the chief ray (µm)."""
        return grid_offsets(self.size, self.pitch_um)

    @property
    def y_um(self) -> np.ndarray:
        """Row centres relative to the chief ray (µm), top row first."""
        return -grid_offsets(self.size, self.pitch_um)

    def write(self, path: str) -> None:
        """Write the PSF as OpenEXR, whole or not at all: channel "Y", all metadata in the header.

        Parameters
        ----------
        path : str
            The file.
        """
        from ..imageio import write_exr

        meta = dict(
            self.meta,
            field_deg=list(self.field_deg),
            wavelengths_nm=list(self.wavelengths_nm),
            weights=list(self.weights),
            pitch_um=self.pitch_um,
            size=self.size,
            chief_ray_origin_mm=list(self.chief_ray_mm),
        )
        write_exr(path, {"Y": self.data}, meta)

    def write_png(self, path: str) -> None:
        """Write the PSF scaled to its peak as an sRGB PNG, for viewing.

        Parameters
        ----------
        path : str
            The file.
        """
        from ..imageio import write_png

        write_png(path, self.data / max(float(self.data.max()), 1e-300))


@dataclass(frozen=True, kw_only=True)
class Computed:
    """What a PSF method computes for n field/wavelength pairs (`registry`), by name."""

    data: np.ndarray  # (n, size, size) PSFs in 1/µm² (irradiance per µm² / on-axis entrance-pupil power)
    chief: Any  # optics.pupil.ChiefRays of the pairs
    transmission: np.ndarray  # (n,) transmitted power, fraction of the on-axis entrance-pupil power
    vignetted_by: list  # per pair: 1-based surfaces that block part of the pupil
    warnings: tuple = ()  # what the method found doubtful (e.g. under-sampling), one line each
    centre_um: np.ndarray | None = None  # (n, 2) each window's centre less its chief ray's image point


# A PSF window holding less than this fraction of the transmitted light (or, from aliasing, more than
# its inverse) is reported: its normalised PSF would hide the loss. The default sampling of the shipped
# doublet keeps 94.9–98 % (Fraunhofer diffraction tails beyond ±40 µm); losing more is worth a word.
WINDOW_ENERGY_LIMIT = 0.94


def window_energy(data: np.ndarray, pitch_um: float, transmission: np.ndarray) -> np.ndarray:
    """Fraction of each PSF's transmitted power (…, size, size in 1/µm²) inside its window."""
    return energy_of_sum(data.sum(axis=(-2, -1)), pitch_um, transmission)


def energy_of_sum(total: np.ndarray, pitch_um: float, transmission: np.ndarray) -> np.ndarray:
    """`window_energy` of PSFs whose window sums (1/µm²) are `total`."""
    return total * pitch_um**2 / np.where(transmission > 0, transmission, 1.0)


def window_warnings(energy: ArrayLike, fields_deg: np.ndarray, size: int, pitch_um: float) -> list[str]:
    """A warning for the PSF whose window energy is furthest from 1, if any is outside the limits."""
    energy = np.asarray(energy, dtype=np.float64).ravel()
    fields = np.asarray(fields_deg, dtype=np.float64).reshape(-1, 2)
    low, high = energy < WINDOW_ENERGY_LIMIT, energy > 1.0 / WINDOW_ENERGY_LIMIT
    if not (low.any() or high.any()):
        return []
    i = int(np.argmax(np.abs(np.log(np.maximum(energy, 1e-300)))))
    fx, fy = fields[i % len(fields)]
    if energy[i] < 1.0:
        return [
            f"the {size}x{size} window of {pitch_um:g} um holds only {100 * energy[i]:.1f} % of the transmitted "
            f"light at field ({fx:g}, {fy:g}) deg ({_count(low)} below {100 * WINDOW_ENERGY_LIMIT:g} %): "
            "normalised PSFs hide the rest; enlarge --size or --pitch-um (or --auto-window)"
        ]
    return [
        f"the PSF at field ({fx:g}, {fy:g}) deg holds {100 * energy[i]:.1f} % of the transmitted light in its "
        f"window ({_count(high)} above {100 / WINDOW_ENERGY_LIMIT:.0f} %): aliasing from an under-sampled "
        "pupil; raise --pupil-samples as the sampling warning advises (its --psf-method geometric where "
        "no allowed count resolves the wavefront)"
    ]


def _count(mask: np.ndarray) -> str:
    n = int(mask.sum())
    return f"{n} PSF{'' if n == 1 else 's'}"


def window_centres_um(chief, light_um: np.ndarray | None, shared_origin: bool) -> np.ndarray | None:
    """Offsets (n, 2) in µm from each chief ray's image point to its window's centre: the first chief
    ray's point for all (`shared_origin`), moved to the centroid of the arriving light where a chief
    ray is blocked (`light_um`, from `geometric.light_offsets_um`); None when every window sits on its
    own chief ray."""
    if light_um is None:
        return shared_origin_um(chief.image_xy) if shared_origin else None
    return shared_origin_um(chief.image_xy) + light_um[:1] if shared_origin else light_um


def centring_warnings(chief, light_um: np.ndarray | None, fields_deg: np.ndarray) -> list[str]:
    """A line for the fields whose window is centred on the arriving light instead of the blocked chief ray."""
    if light_um is None:
        return []
    i = int(np.argmax(np.hypot(*light_um.T)))
    fx, fy = np.atleast_2d(fields_deg)[i]
    return [
        f"the chief ray is blocked at {int(chief.vignetted.sum())} field(s) (e.g. ({fx:g}, {fy:g}) deg): their "
        f"PSF windows are centred on the light that arrives, up to {np.hypot(*light_um[i]):.1f} um from the "
        "chief ray (meta centre)"
    ]


def shared_origin_um(image_xy: np.ndarray) -> np.ndarray:
    """Offsets (n, 2) in µm that put every grid's origin on the first chief ray's image point."""
    return (image_xy[:1] - image_xy) * 1e3


def grid_offsets(size: int, pitch_um: float) -> np.ndarray:
    """Pixel-centre offsets (µm) from the grid origin at index size//2, increasing."""
    return (np.arange(size) - size // 2) * pitch_um


MAX_SIZE = 8192  # pixels


def check_grid(pitch_um: float, size: int) -> None:
    if not isinstance(size, (int, np.integer)) or isinstance(size, bool) or not 2 <= size <= MAX_SIZE:
        raise SolasError(f"PSF size {size!r} must be an integer from 2 to {MAX_SIZE} pixels")
    if (
        not isinstance(pitch_um, (int, float, np.integer, np.floating))
        or isinstance(pitch_um, bool)
        or not math.isfinite(pitch_um)
        or pitch_um <= 0
    ):
        raise SolasError(f"PSF pitch {pitch_um!r} µm must be a positive number")


def check_lens(lens) -> None:
    from ..optics.lens import Lens

    if not isinstance(lens, Lens):
        raise SolasError(f"lens {lens!r} must be a Lens (solas_mi.Lens.load(a shipped name or a lens file))")


def check_wavelengths(lens, wavelength_nm) -> tuple[float, ...]:
    """One wavelength (nm, a number) or a sequence of them, each checked against the lens's glasses."""
    if isinstance(wavelength_nm, np.ndarray):
        values = wavelength_nm.ravel().tolist()
    elif isinstance(wavelength_nm, (list, tuple)):
        values = list(wavelength_nm)
    else:
        values = [wavelength_nm]
    if not values:
        raise SolasError("at least one wavelength (nm) is needed")
    return tuple(lens.check_wavelength(w) for w in values)


def check_normalization(how: str) -> None:
    if not isinstance(how, str) or how not in NORMALIZATIONS:
        raise SolasError(f"normalization {how!r} must be one of {', '.join(NORMALIZATIONS)}")


def normalize(data: np.ndarray, how: str) -> np.ndarray:
    """Normalise PSFs over the last two axes: "sum", "peak" or "none"."""
    check_normalization(how)
    if how == "none":
        return data
    scale = data.sum(axis=(-2, -1), keepdims=True) if how == "sum" else data.max(axis=(-2, -1), keepdims=True)
    return data / np.where(scale > 0, scale, 1.0)


def describe(lens, method: str, normalization: str, sampling: dict, size: int) -> dict:
    """The metadata every PSF output carries: lens, method, sampling (its parameter and value) and
    array conventions."""
    return {
        "lens": lens.name,
        "lens_hash": lens.hash,
        "lens_source": lens.source,
        "lens_dispersion": lens.dispersive,
        **notes.metadata(lens),
        "method": method,
        "normalization": normalization,
        "values": VALUE_MEANING[normalization],
        "sampling": dict(sampling),
        "origin_pixel": [size // 2, size // 2],
        "orientation": "row 0 = top (largest y), column 0 = left (smallest x)",
    }


@lru_cache(maxsize=1)
def thread_pool() -> ThreadPoolExecutor:
    """One thread per core this process may use, kept for the process (matrix products and the placing of
    a grid's nodes; starting threads each time took 3 ms a thread on a loaded machine)."""
    return ThreadPoolExecutor(cores(), thread_name_prefix="solas-psf")


def in_threads(work, parts: list) -> None:
    """`work(part)` for each of `parts` on the pool's threads, the parts dealt out in turn; returns when all are done."""
    n = min(len(parts), threads())  # a batch worker's share of the cores (`cores.use_share`)
    if n <= 1:
        for part in parts:
            work(part)
        return
    list(thread_pool().map(lambda k: [work(p) for p in parts[k::n]], range(n)))
