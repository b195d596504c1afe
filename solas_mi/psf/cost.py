"""What a PSF grid will take to compute, said before it is computed (`batch degrade --dry-run`).

Measured on this grid, not modelled: the cost of a PSF depends on the lens (its surfaces, the ray
aiming its field needs), the method, the pupil samples, the size and the machine. The grid is computed
(`nodes.compute_nodes`) in calls of the distinct fields of every wavelength together, as many as hold
`nodes.BATCH_RAYS` pupil rays (`nodes.batch_sizes`; mirror images of a field are copied, not computed), and a
call costs a fixed part (tracing set-up, ray
aiming, the DFT matrices; a call lasts as long as its hardest field needs) and a part per PSF. After
a call that compiles the tracer's kernels, a call of the grid's first and last fields and one of
CALIBRATION_FIELDS fields spread over the grid give both parts, and the grid's calls are summed:
distances × its batches. Measured on the shared 2-core
machine (a load of 3-10), the estimate came within a factor of about 1.5 of the grid's time (doublet,
32×32 Fraunhofer: estimated 7.1 s, took 6.4 s; see `docs/details/batch.md`). `--auto-window` may
compute the grid again at twice the size, which the estimate does not include.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from .base import check_wavelengths
from .depth import at_distance
from .grid import grid_fields
from .methods import compute
from .nodes import batch_sizes, symmetry_classes
from .spec import GridSpec

CALIBRATION_FIELDS = 8


@dataclass(frozen=True)
class GridCost:
    """The estimate and how it was derived."""

    seconds: float
    computed: int  # PSFs to compute: distinct fields × wavelengths × distances
    total: int  # the grid's PSFs, mirror images included
    calls: int  # calls of `methods.compute`
    per_call_s: float  # measured: the fixed part of a call
    per_psf_s: float  # measured: each PSF of a call
    timed: int  # PSFs timed for it

    def text(self) -> str:
        return (
            f"about {self.seconds:.3g} s: {self.computed} PSFs to compute of its {self.total} (the others are "
            f"mirror images) in {self.calls} calls of {self.per_call_s:.2g} s + {self.per_psf_s:.2g} s per PSF, "
            f"as timed now on {self.timed} of its PSFs"
        )


def grid_cost(lens, spec: GridSpec) -> GridCost:
    """The time `psf.depth.make_grid(lens, spec)` will take on this machine, from a few of its PSFs
    computed now (a second or two for most grids; the fixed part of three calls where it is large)."""
    wavelengths = check_wavelengths(lens, spec.wavelengths_nm or lens.wavelengths_nm)
    distances = spec.distances_m or (None,)
    near = lens if distances[0] is None else at_distance(lens, distances[0])
    one = replace(spec, distances_m=None)
    fields, _ = grid_fields(near, one)
    canon = symmetry_classes(fields.reshape(-1, 2))[0]
    odd = 2 * (spec.size // 2) + 1  # as `compute_nodes` computes them

    def seconds(picked) -> float:
        start = time.perf_counter()
        compute(
            near,
            canon[picked],
            np.full(len(picked), wavelengths[0]),
            spec.pitch_um,
            odd,
            spec.method,
            **spec.sampling_options(),
        )
        return time.perf_counter() - start

    seconds([len(canon) // 2])  # compiles the kernels (once per machine; Dr.Jit caches them)
    # both calls hold the first and the last field: a call lasts as long as its hardest field needs (the
    # ray aiming of a wide field), a fixed part, and the spread fields add what each PSF costs
    ends = np.unique([0, len(canon) - 1])
    spread = np.unique(np.linspace(0, len(canon) - 1, min(CALIBRATION_FIELDS, len(canon))).round().astype(int))
    two, several = seconds(ends), seconds(spread) if len(spread) > len(ends) else None
    per_psf = max(several - two, 0.0) / (len(spread) - len(ends)) if several is not None else two / len(ends)
    per_call = max(two - per_psf * len(ends), 0.0)
    batches = batch_sizes(spec, len(wavelengths) * len(canon))
    repeats = len(distances)
    return GridCost(
        repeats * sum(per_call + per_psf * b for b in batches),
        repeats * len(wavelengths) * len(canon),
        repeats * len(wavelengths) * fields.shape[0] * fields.shape[1],
        repeats * len(batches),
        per_call,
        per_psf,
        1 + len(ends) + len(spread) * (several is not None),
    )
