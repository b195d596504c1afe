"""`GhostGrid`, the ghosts of a lens over the field (`ghost_nodes.ghost_grid` computes one), and its file: OpenEXR
(each wavelength's kernels as one mosaic channel, the rest in the metadata) with the same metadata as JSON beside
it. `GhostGrid.at` gives the ghosts of any field, `NodeGhosts.image` their irradiance on the sensor.

Each ghost is kept as its energy, its centroid on the image plane and a small kernel about that centroid at its
own pitch, not as a ghost image of the whole sensor: a ghost moves far across the sensor as the field changes, so
a field between nodes takes each ghost's centroid, energy and shape interpolated between the nodes (the ghost
moves), where blending two sensor images would fade one ghost out at one place and in at another; and a wide,
defocused ghost and a focused one each fit the same number of pixels.

Nodes lie along one radius of the field, polar angles 0 … the grid's field, at the azimuth 90° (the +y axis).
The lens is centred: the ghosts of a field at azimuth φ are those of the node at the same polar angle turned by
φ − 90° about the axis. An iris breaks that symmetry down to its N blades: its grid also has nodes at `azimuths`
azimuths over one blade's sector (360°/N), and a field takes the two nearest azimuths of its sector too, each
turned by the whole sectors between (exact) and the rest of the angle (an approximation of the iris's turn).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..errors import SolasError

# the options of `ghost_nodes.ghost_grid` (here, where the light command line reads them)
DEFAULT_RADII = 9  # nodes along the field's radius, 0 to the grid's field
MAX_RADII = 64
DEFAULT_KERNEL = 63  # pixels per side of each ghost's kernel: odd, symmetric about its centroid's pixel, so that
KERNEL_RANGE = (9, 511)  # a kernel turned by 90 deg or mirrored stays on its grid (as `nodes`'s PSFs)
DEFAULT_IRIS_AZIMUTHS = 4  # an iris's nodes per blade sector (a round stop: 1, the ghosts turn with the field)
MAX_AZIMUTHS = 32
OFFSET_KEYS = ("polar_deg", "azimuth_deg", "energy", "centroid_mm", "pitch_um", "direct_mm")


@dataclass
class NodeGhosts:
    """The ghosts of one field, per wavelength and path (`GhostGrid.node`, `GhostGrid.at`).

    Parameters
    ----------
    energy : numpy.ndarray
        (wavelengths, paths): each ghost's energy as a fraction of the direct image's at that wavelength.
    centroid_mm : numpy.ndarray
        (wavelengths, paths, 2): its centroid (x, y) on the image plane (mm).
    pitch_um : numpy.ndarray
        (wavelengths, paths): its kernel's pixel pitch (µm).
    kernels : numpy.ndarray
        (wavelengths, paths, k, k): its irradiance about its centroid, each summing to 1 (zero where the
        ghost has no energy), row 0 the top (+y), the centroid at pixel (k // 2, k // 2) as `psf.base`'s PSFs.
    direct_mm : numpy.ndarray
        (wavelengths, 2): the direct image's centroid (mm).
    """

    energy: np.ndarray
    centroid_mm: np.ndarray
    pitch_um: np.ndarray
    kernels: np.ndarray
    direct_mm: np.ndarray

    def image(self, pitch_um: float, size: int, centre_mm=None) -> np.ndarray:
        """Every ghost together on a size × size grid of the image plane, per wavelength.

        Parameters
        ----------
        pitch_um : float
            The grid's pixel pitch (µm).
        size : int
            Pixels per side.
        centre_mm : (float, float), optional
            The image point (mm) at pixel (size // 2, size // 2); default: the first wavelength's direct image.

        Returns
        -------
        numpy.ndarray
            (wavelengths, size, size): fractions of the direct image's energy per pixel (light beyond the grid
            is left out), row 0 the top.
        """
        from .base import check_grid

        check_grid(pitch_um, size)
        cx, cy = self.direct_mm[0] if centre_mm is None else centre_mm
        out = np.zeros((len(self.energy), size, size))
        k = self.kernels.shape[-1]
        for w, p in zip(*np.nonzero(self.energy > 0)):
            pitch = float(self.pitch_um[w, p])
            x0, y0 = (self.centroid_mm[w, p] - (cx, cy)) * 1e3  # µm from the grid's centre
            cols, across = kernel_overlap(x0, pitch, k, pitch_um, size)
            rows, down = kernel_overlap(-y0, pitch, k, pitch_um, size)  # rows run down from +y
            if len(cols) and len(rows):
                spread = (across @ self.kernels[w, p].T).T  # sparse products: each grid pixel meets few kernel pixels
                out[w, rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1] += self.energy[w, p] * (down @ spread)
        return out


@dataclass
class GhostGrid:
    """The ghosts of a lens on nodes along the field's radius (module docstring), as `ghost_grid` computes them.

    Parameters
    ----------
    polar_deg : numpy.ndarray
        (radii,): the nodes' polar angles (degrees), from 0 increasing.
    azimuth_deg : numpy.ndarray
        (azimuths,): the nodes' azimuths (degrees from +x, counter-clockwise seen from the object): 90 (the +y
        axis), and for an iris more over one blade's sector.
    sector_deg : float
        The angle the lens repeats after: 360 (round stop), 360 / N (an iris of N blades).
    wavelengths_nm : tuple of float
        The wavelengths (nm).
    paths : list of (int, int)
        The ghost paths: the surfaces (1-based) they reflect at, first j then i.
    energy, centroid_mm, pitch_um : numpy.ndarray
        (wavelengths, azimuths, radii, paths[, 2]): as `NodeGhosts`'s, per node.
    kernels : numpy.ndarray
        (wavelengths, azimuths, radii, paths, k, k) float32: as `NodeGhosts`'s, per node.
    direct_mm : numpy.ndarray
        (wavelengths, azimuths, radii, 2): the direct image's centroid per node (mm).
    meta : dict, optional
        The lens, the options, the field type ("field_type"), the nodes' fields ("fields_deg").
    """

    polar_deg: np.ndarray
    azimuth_deg: np.ndarray
    sector_deg: float
    wavelengths_nm: tuple[float, ...]
    paths: list
    energy: np.ndarray
    centroid_mm: np.ndarray
    pitch_um: np.ndarray
    kernels: np.ndarray
    direct_mm: np.ndarray
    meta: dict = field(default_factory=dict)

    def node(self, a: int, r: int) -> NodeGhosts:
        """The ghosts of one node as computed.

        Parameters
        ----------
        a : int
            Its azimuth's index in `azimuth_deg`.
        r : int
            Its radius's index in `polar_deg`.

        Returns
        -------
        NodeGhosts
            Its ghosts.
        """
        return NodeGhosts(
            self.energy[:, a, r],
            self.centroid_mm[:, a, r],
            self.pitch_um[:, a, r],
            self.kernels[:, a, r].astype(np.float64),
            self.direct_mm[:, a, r],
        )

    def corners(self, field_deg) -> list[tuple[int, int, float, float]]:
        """The nodes a field takes.

        Parameters
        ----------
        field_deg : (float, float)
            The field (x, y) in degrees.

        Returns
        -------
        list of tuple
            (azimuth index, radius index, weight, the angle (radians) to turn the node's ghosts by), weights
            summing to 1.

        Raises
        ------
        SolasError
            For a field beyond the grid's polar angle.
        """
        from ..optics.fields import FIELD_TYPES

        theta, phi = FIELD_TYPES[self.meta["field_type"]].polar(field_deg)
        theta = math.degrees(theta)
        if theta > self.polar_deg[-1] * (1.0 + 1e-9):
            raise SolasError(
                f"field ({field_deg[0]:g}, {field_deg[1]:g}) deg: its polar angle {theta:g} deg is beyond the ghost "
                f"grid's {self.polar_deg[-1]:g} deg"
            )
        r0 = int(np.clip(np.searchsorted(self.polar_deg, theta) - 1, 0, len(self.polar_deg) - 2))
        t = float(np.clip((theta - self.polar_deg[r0]) / (self.polar_deg[r0 + 1] - self.polar_deg[r0]), 0.0, 1.0))
        step = self.sector_deg / len(self.azimuth_deg)
        turn = math.degrees(phi) - self.azimuth_deg[0]  # from the first node's azimuth
        rest = turn % self.sector_deg  # within its sector: the lens repeats after a whole one
        a0 = min(int(rest // step), len(self.azimuth_deg) - 1)
        s = rest / step - a0 if len(self.azimuth_deg) > 1 else 0.0
        out = []
        for a, wa in ((a0, 1.0 - s), (a0 + 1, s)):
            for r, wr in ((r0, 1.0 - t), (r0 + 1, t)):
                if wa * wr > 0:
                    out.append((a % len(self.azimuth_deg), r, wa * wr, math.radians(turn - a * step)))
        return out

    def at(self, field_deg) -> NodeGhosts:
        """The ghosts of any field within the grid: its nodes' (`corners`) turned to its azimuth, their energies,
        centroids, pitches and kernels (in each ghost's own frame about its centroid) interpolated.

        Parameters
        ----------
        field_deg : (float, float)
            The field (x, y) in degrees, its polar angle within the grid's.

        Returns
        -------
        NodeGhosts
            Its ghosts.

        Raises
        ------
        SolasError
            For a field beyond the grid.
        """
        from scipy.ndimage import map_coordinates

        parts = [(self.node(a, r), w, turn) for a, r, w, turn in self.corners(field_deg)]
        energy = np.sum([w * g.energy for g, w, _ in parts], axis=0)
        lit = [(w * (g.energy > 0), g) for g, w, _ in parts]
        share = sum(w for w, _ in lit)
        share = np.where(share > 0, share, 1.0)
        centroid = (
            sum(w[..., None] * _turn(g.centroid_mm, turn) for (w, g), (_, _, turn) in zip(lit, parts))
            / share[..., None]
        )
        pitch = np.where(energy > 0, sum(w * g.pitch_um for w, g in lit) / share, 1.0)
        direct = np.sum([w * _turn(g.direct_mm, turn) for g, w, turn in parts], axis=0)
        k = self.kernels.shape[-1]
        offsets = np.arange(k) - k // 2
        col, row = np.meshgrid(offsets, offsets)  # the output's pixels, in units of its pitch (row: −y)
        kernels = np.zeros((*energy.shape, k, k))
        for (w, g), (_, _, turn) in zip(lit, parts):
            for wl, p in zip(*np.nonzero(w > 0)):
                scale = pitch[wl, p] / g.pitch_um[wl, p]
                c, s = math.cos(turn), math.sin(turn)  # each pixel (col, −row) turned back onto the node's kernel
                u, v = (c * col - s * row) * scale, (-s * col - c * row) * scale
                sampled = map_coordinates(g.kernels[wl, p], [k // 2 - v, k // 2 + u], order=1, cval=0.0)
                kernels[wl, p] += w[wl, p] * sampled * scale**2
        sums = kernels.sum(axis=(2, 3), keepdims=True)
        return NodeGhosts(energy, centroid, pitch, kernels / np.where(sums > 0, sums, 1.0), direct)

    def only(self, path: int) -> GhostGrid:
        """The grid of one ghost path: that path's ghosts alone, at every node and wavelength.

        Parameters
        ----------
        path : int
            The path's index into `paths`.

        Returns
        -------
        GhostGrid
            The same grid holding only that path (its energies, centroids, pitches and kernels).
        """
        keep = slice(path, path + 1)
        return replace(self, paths=self.paths[keep], energy=self.energy[..., keep],
                       centroid_mm=self.centroid_mm[..., keep, :], pitch_um=self.pitch_um[..., keep],
                       kernels=self.kernels[..., keep, :, :])  # fmt: skip

    @property
    def size(self) -> int:
        """Pixels per side of each kernel."""
        return self.kernels.shape[-1]

    def arrays_meta(self) -> dict:
        """Everything but the kernels, as JSON values (the file's metadata, `write`).

        Returns
        -------
        dict
            `meta` with the arrays, wavelengths, paths, sector and kernel size.
        """
        meta = dict(self.meta)
        meta.update({key: np.asarray(getattr(self, key)).tolist() for key in OFFSET_KEYS})
        meta.update(
            sector_deg=self.sector_deg,
            wavelengths_nm=list(self.wavelengths_nm),
            paths=[list(p) for p in self.paths],
            kernel_size=self.size,
        )
        return meta

    def write(self, path, json_path=None) -> None:
        """Write the grid as OpenEXR (a channel per wavelength, "ghosts_531nm": the kernels as a mosaic, rows
        azimuth, radius, kernel row; columns path, kernel column) with the rest in its metadata; and the same
        metadata as JSON at `json_path` where given; whole or not at all.

        Parameters
        ----------
        path : str or PathLike
            The EXR file.
        json_path : str or PathLike, optional
            The JSON file of its metadata.
        """
        from .. import jsonio
        from ..imageio import write_exr
        from ..outputs import written_together

        meta = self.arrays_meta()
        w, a, r, p, k, _ = self.kernels.shape
        mosaic = self.kernels.transpose(0, 1, 2, 4, 3, 5).reshape(w, a * r * k, p * k)
        channels = {f"ghosts_{wl:g}nm": mosaic[i] for i, wl in enumerate(self.wavelengths_nm)}
        targets = [path] + ([json_path] if json_path is not None else [])
        with written_together(*targets) as tmps:
            write_exr(tmps[0], channels, meta)
            if json_path is not None:
                with open(tmps[1], "w") as f:
                    f.write(jsonio.dumps(meta, indent=1) + "\n")

    @classmethod
    def read(cls, path) -> GhostGrid:
        """Read a grid `write` wrote.

        Parameters
        ----------
        path : str or PathLike
            The EXR file.

        Returns
        -------
        GhostGrid
            The grid.

        Raises
        ------
        SolasError
            For a file that is not a ghost grid, or whose metadata or channels do not fit.
        """
        from ..imageio import read_exr

        channels, meta = read_exr(path)
        if not isinstance(meta, dict) or "paths" not in meta or "kernel_size" not in meta:
            raise SolasError(f"{path} is not a solas-mi ghost grid (no ghost grid metadata)")
        try:
            arrays = {key: np.asarray(meta.pop(key), dtype=np.float64) for key in OFFSET_KEYS}
            wl, k = tuple(float(x) for x in meta.pop("wavelengths_nm")), int(meta.pop("kernel_size"))
            paths = [tuple(int(i) for i in p) for p in meta.pop("paths")]
            sector = float(meta.pop("sector_deg"))
            shape = (len(arrays["azimuth_deg"]), len(arrays["polar_deg"]), len(paths))
            stacks = [channels[f"ghosts_{w:g}nm"].reshape(shape[0], shape[1], k, shape[2], k) for w in wl]
        except (KeyError, TypeError, ValueError) as exc:
            raise SolasError(f"ghost grid {path}: damaged metadata or channels ({type(exc).__name__}: {exc})") from None
        kernels = np.stack(stacks).transpose(0, 1, 2, 4, 3, 5)
        return cls(
            arrays["polar_deg"], arrays["azimuth_deg"], sector, wl, paths, arrays["energy"], arrays["centroid_mm"],
            arrays["pitch_um"], kernels, arrays["direct_mm"], meta
        )  # fmt: skip


def kernel_overlap(centre: float, pitch: float, k: int, grid_pitch: float, size: int) -> tuple[np.ndarray, Any]:
    """Along one axis, the pixels of a size-pixel grid (centred on pixel size // 2) that a k-pixel kernel (centred
    at `centre`, µm, on its pixel k // 2) covers, and the share of each kernel pixel each of them holds (their
    overlap over the kernel's pitch): a kernel's light resampled onto the grid by area, none lost inside it."""
    kernel = centre + (np.arange(k + 1) - k // 2 - 0.5) * pitch  # its pixels' edges
    first = max(0, int(math.floor(kernel[0] / grid_pitch + size // 2 + 0.5)))
    last = min(size - 1, int(math.ceil(kernel[-1] / grid_pitch + size // 2 - 0.5)))
    from scipy.sparse import csr_array

    grid = (np.arange(first, last + 2) - size // 2 - 0.5) * grid_pitch
    share = np.minimum(grid[1:, None], kernel[None, 1:]) - np.maximum(grid[:-1, None], kernel[None, :-1])
    return np.arange(first, last + 1), csr_array(np.maximum(share, 0.0) / pitch)


def _turn(xy: np.ndarray, angle: float) -> np.ndarray:
    """Points (…, 2) turned by `angle` (radians) about the axis, counter-clockwise."""
    c, s = math.cos(angle), math.sin(angle)
    return np.stack([c * xy[..., 0] - s * xy[..., 1], s * xy[..., 0] + c * xy[..., 1]], axis=-1)
