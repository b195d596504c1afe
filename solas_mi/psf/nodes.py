"""The PSFs of a grid's nodes (`compute_nodes`, for `grid.psf_grid`): each distinct |field| pair of a
centred lens (`symmetry_classes`) computed once, every wavelength's together in calls of at most
BATCH_RAYS pupil rays (`batch_sizes`), and turned onto its nodes (`place`: mirrored, transposed, cut to
size and normalised, in threads).

The lens is centred (every surface is rotationally symmetric about the axis), so the PSF of field
(−x, y) is the mirror image of that of (x, y), and that of (y, x) its transpose: each distinct pair is
computed on an odd window, symmetric about the chief ray, and mirrored.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..optics.lens import Lens
from ..threads import in_threads
from . import base
from .methods import compute
from .spec import GridSpec


def symmetry_classes(fields: np.ndarray, decimals: int = 12):
    """Fields (n, 2) reduced by the mirror and diagonal symmetries of a centred lens.

    Returns the canonical fields (m, 2) with x ≥ y ≥ 0, and for each input field the index of its
    canonical field, whether x and y are swapped, and the signs (n, 2) that map canonical to input."""
    ax = np.abs(fields)
    swap = ax[:, 1] > ax[:, 0]
    key = np.round(np.where(swap[:, None], ax[:, ::-1], ax), decimals)
    canon, which = np.unique(key, axis=0, return_inverse=True)
    sign = np.where(fields < 0, -1.0, 1.0)
    return canon, which.ravel(), swap, sign


@dataclass(frozen=True)
class Nodes:
    """What `compute_nodes` gives: the PSFs and, per wavelength and node (flat), their data."""

    data: np.ndarray  # (n_wavelengths, ny, nx, size, size), normalised
    chief: np.ndarray  # (n_wavelengths, n, 2) image point at each PSF's origin pixel, mm
    transmission: np.ndarray  # (n_wavelengths, n)
    energy: np.ndarray  # (n_wavelengths, n) fraction of the transmitted light inside the window
    vignetting: tuple[int, ...]  # surfaces that block part of some pupil
    doubts: tuple[str, ...]  # the methods' warnings, each once


def compute_nodes(
    lens: Lens, spec: GridSpec, wl: tuple[float, ...], flat: np.ndarray, size: int, progress=None
) -> Nodes:
    """The PSFs of fields `flat` (n, 2) at wavelengths `wl`, size×size: each distinct |field| pair
    (`symmetry_classes`) computed once, every wavelength's together in batches of at most `BATCH_RAYS` pupil
    rays, and mirrored onto its nodes."""
    ny, nx = spec.grid
    n = len(flat)
    canon, which, swap, sign = symmetry_classes(flat)
    odd = 2 * (size // 2) + 1  # symmetric about the origin pixel, so mirrors stay on the grid
    # stored as the EXR's mosaics (wavelength, row, y, column, x), the layout `read` gives too, so that
    # writing needs no copy; `data` (wavelength, row, column, y, x) is a view of it
    data = np.zeros((len(wl), ny, size, nx, size), dtype=np.float32).transpose(0, 1, 3, 2, 4)
    chief, transmission, energy = np.zeros((len(wl), n, 2)), np.zeros((len(wl), n)), np.zeros((len(wl), n))
    vignetting: set[int] = set()
    doubts: list[str] = []
    # every (wavelength, canonical field) pair, in batches across wavelengths
    pairs = np.stack(np.meshgrid(np.arange(len(wl)), np.arange(len(canon)), indexing="ij"), axis=-1).reshape(-1, 2)
    done = 0
    for part in np.array_split(pairs, len(batch_sizes(spec, len(pairs)))):
        c = compute(
            lens,
            canon[part[:, 1]],
            np.asarray(wl)[part[:, 0]],
            spec.pitch_um,
            odd,
            spec.method,
            **spec.sampling_options(),
        )
        vignetting.update(s for v in c.vignetted_by for s in v)
        doubts.extend(d for d in c.warnings if d not in doubts)
        for k in np.unique(part[:, 0]):
            mine = np.flatnonzero(part[:, 0] == k)  # this wavelength's PSFs in the batch
            lookup = np.full(len(canon), -1)
            lookup[part[mine, 1]] = mine
            nodes = np.flatnonzero(lookup[which] >= 0)
            j = lookup[which[nodes]]
            xy = c.chief.image_xy[j] + (0.0 if c.centre_um is None else c.centre_um[j] * 1e-3)
            chief[k, nodes] = np.where(swap[nodes, None], xy[:, ::-1], xy) * sign[nodes]
            transmission[k, nodes] = c.transmission[j]
            turns = np.stack([swap[nodes], sign[nodes, 0] < 0, sign[nodes, 1] < 0], axis=1)
            energy[k, nodes] = place(
                c.data, c.transmission, nodes, j, turns, data[k], spec.normalization, spec.pitch_um
            )
            done += len(nodes)
        if progress is not None:  # in nodes: the PSFs of the grid, mirrored ones included
            progress(done, len(wl) * n)
    return Nodes(data, chief, transmission, energy, tuple(sorted(vignetting)), tuple(doubts))


def batch_sizes(spec: GridSpec, psfs: int) -> list[int]:
    """The PSFs of each call of `methods.compute` that a grid's `psfs` distinct PSFs (every wavelength's)
    are computed in (`compute_nodes`): as few calls as hold at most BATCH_RAYS pupil rays each."""
    per_psf = spec.pupil_samples**2 if spec.method == "fraunhofer" else spec.rays**2
    return [len(part) for part in np.array_split(np.arange(psfs), max(1, -(-psfs * per_psf // BATCH_RAYS)))]


BATCH_RAYS = 1 << 20  # pupil rays of one batch of PSFs (64 of 128²): measured on the doublet's 32x32x3 grid,
# 2^20 ran it in 0.6 s of Dr.Jit kernels against 1.1 s at 2^22 (working arrays that stay in cache, memory
# that Dr.Jit reuses from batch to batch) and 1.2 s at 2^18 (more, smaller kernels)


def place(
    psfs: np.ndarray,
    transmission: np.ndarray,
    nodes: np.ndarray,
    source: np.ndarray,
    turns: np.ndarray,
    out: np.ndarray,
    normalization: str,
    pitch_um: float,
) -> np.ndarray:
    """Canonical PSFs `psfs` (m, odd, odd) turned onto grid nodes: node `nodes[i]` (row-major in `out`, (ny, nx,
    size, size) float32) gets PSF `source[i]` turned by `turns[i]` (swap, flip x, flip y: `_turned`), cut to
    size × size and normalised; in threads (NumPy lets go of the GIL). Returns each node's fraction of its
    transmitted light in its window."""
    nx, size = out.shape[1], out.shape[-1]
    energy = np.empty(len(nodes))
    single = psfs.astype(np.float32)  # products in float32 (measured: a cast in the product holds the GIL)
    flat, total = psfs.reshape(len(psfs), -1), psfs.sum(axis=(1, 2))
    jobs = []
    for key in {tuple(t) for t in turns.tolist()}:
        mine = np.flatnonzero((turns == key).all(axis=1))
        turned = _turned(psfs, *key)[:, :size, :size]  # views: (m, size, size)
        used = np.unique(source[mine])
        sums, scale = total - _cut(flat, psfs.shape[-1], size, key), np.ones(len(psfs))
        if normalization != "none":
            scale[used] = sums[used] if normalization == "sum" else turned[used].max(axis=(1, 2))
        scale = (1.0 / np.where(scale > 0, scale, 1.0)).astype(np.float32)
        energy[mine] = base.energy_of_sum(sums[source[mine]], pitch_um, transmission[source[mine]])
        turned = _turned(single, *key)[:, :size, :size]
        jobs += [(turned[source[i]], scale[source[i]], out[nodes[i] // nx, nodes[i] % nx]) for i in mine]

    in_threads(lambda job: np.multiply(job[0], job[1], out=job[2]), jobs)
    return energy


def _cut(flat: np.ndarray, odd: int, size: int, key: tuple) -> np.ndarray:
    """Per PSF (rows of `flat`, odd² values) the sum of what cutting its turned window (`_turned` by `key`)
    to size × size leaves out: its last row and column."""
    if odd == size:
        return np.zeros(len(flat))
    where = _turned(np.arange(odd * odd).reshape(odd, odd), *key)
    row, col = where[size:, :].ravel(), where[:size, size:].ravel()
    return flat[:, row].sum(axis=1) + flat[:, col].sum(axis=1)


def _turned(p: np.ndarray, swap: bool, flip_x: bool, flip_y: bool) -> np.ndarray:
    """PSFs (…, y, x) transposed where x and y swap (about the centre pixel: flipped both ways, then
    transposed), then mirrored left-right (`flip_x`) and top-bottom (`flip_y`): views."""
    if swap:
        p = p[..., ::-1, ::-1].swapaxes(-1, -2)
    if flip_x:
        p = p[..., :, ::-1]
    if flip_y:
        p = p[..., ::-1, :]
    return p
