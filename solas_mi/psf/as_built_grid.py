"""The PSFs of a grid's nodes for a lens as built (`optics.lens_checks.as_built`, for `grid.psf_grid`): every
node of the whole field traced (`as_built_methods`, the Dr.Jit tracer in local frames), none mirrored, since a decentred or
tilted surface or a placed sensor breaks the mirror symmetries that `nodes.compute_nodes` uses; one wavelength
per call (the Fraunhofer path takes one per window), cut to size and normalised by `nodes.place`.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import SolasError
from ..optics import local_aim
from ..optics.lens import Lens
from . import as_built_methods
from .methods import compute
from .nodes import Nodes, batch_sizes, place
from .spec import GridSpec


def check(lens: Lens, spec: GridSpec, wl: tuple[float, ...]) -> None:
    """SolasError naming what a grid of the lens as built `lens` does not take: a method without its path
    (`as_built_methods.check`), or the sensor layout (its nodes' fields come from the nominal axis's chief rays)."""
    as_built_methods.check(lens, spec.method, wl[0])
    if spec.layout == "sensor":
        raise SolasError(
            f"lens {lens.name} is a lens as built: its PSF grid takes layout 'field' (not {spec.layout!r}: the "
            "sensor layout's fields come from chief rays about the nominal axis)"
        )


def compute_nodes(
    lens: Lens, spec: GridSpec, wl: tuple[float, ...], flat: np.ndarray, size: int, progress=None
) -> Nodes:
    """The PSFs of fields `flat` (n, 2) at wavelengths `wl`, size×size, of the lens as built: every node traced,
    one wavelength per call of `methods.compute`, in batches of at most `nodes.BATCH_RAYS` pupil rays."""
    ny, nx = spec.grid
    n = len(flat)
    odd = 2 * (size // 2) + 1  # the symmetric path's window, so both cut alike
    data = np.zeros((len(wl), ny, size, nx, size), dtype=np.float32).transpose(0, 1, 3, 2, 4)
    chief, transmission, energy = np.zeros((len(wl), n, 2)), np.zeros((len(wl), n)), np.zeros((len(wl), n))
    vignetting: set[int] = set()
    doubts: list[str] = []
    unturned = np.zeros((n, 3), dtype=bool)
    for k, w in enumerate(wl):
        for part in np.array_split(np.arange(n), min(n, len(batch_sizes(spec, n)))):
            c = compute(
                lens, flat[part], np.full(len(part), w), spec.pitch_um, odd, spec.method, **spec.sampling_options()
            )
            vignetting.update(s for v in c.vignetted_by for s in v)
            doubts.extend(d for d in c.warnings if d not in doubts)
            chief[k, part] = c.chief.image_xy + (0.0 if c.centre_um is None else c.centre_um * 1e-3)
            transmission[k, part] = c.transmission
            energy[k, part] = place(
                c.data,
                c.transmission,
                part,
                np.arange(len(part)),
                unturned[part],
                data[k],
                spec.normalization,
                spec.pitch_um,
            )
            if progress is not None:
                progress(k * n + part[-1] + 1, len(wl) * n)
    return Nodes(data, chief, transmission, energy, tuple(sorted(vignetting)), tuple(doubts))


def pinhole_focal_mm(lens: Lens, fov_deg: float) -> float:
    """`optics.camera.pinhole_focal_mm` of the lens as built: the focal length (mm) of the pinhole whose image of
    field (fov_deg, 0) meets the chief ray of the lens as built (`optics.local_aim`) on its image plane, at the
    primary wavelength."""
    chief = local_aim.chief_rays(lens, np.array([[fov_deg, 0.0]]), lens.primary_wavelength)
    if not chief.found[0]:
        raise SolasError(f"lens {lens.name}: no chief ray of the lens as built found at field ({fov_deg:g}, 0) deg")
    return float(chief.image_xy[0, 0]) / math.tan(math.radians(fov_deg))


__all__ = ["check", "compute_nodes", "pinhole_focal_mm"]
