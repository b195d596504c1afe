"""Choosing each lens-camera sample's path through the lens, with `ghosts` on (`lens_camera`): the direct
path or one of the two-reflection ghost paths of `solas_mi.optics.ghost_paths`, traced by
`solas_mi.optics.ghost_trace`.

`ghosts` (a string): "off" (the default: no sampler, the direct image as without this module), "on" (the
direct path with probability `DIRECT_SHARE`, the ghosts with the rest), "only" (the ghosts alone: the
stray light without the direct image) or one path "j,i" (1-based surfaces of the lens file: reflect at j,
then at i < j; that ghost alone).

Among the ghosts, path k is drawn with probability ∝ E_k + `ENERGY_FLOOR`·mean(E), E_k its energy in the
ghost table of the lens on axis (`solas_mi.psf.ghosts`, `TABLE_RAYS`² rays): over a frame, the summed
squared error of the ghosts is least for probabilities ∝ energy (a ghost of energy E spread over area A
adds E²/(A_direct p) to it, whatever A), and the floor keeps every path possible where the on-axis table
finds it dark (a ghost that appears off axis), so the estimate stays unbiased. The sample's weight is
divided by its path's probability. All four spectral lanes of a sample follow its path (each traced at
its own wavelength): lanes on different paths would rarely leave the lens alike, and `lanes_together`
would drop them. The path is drawn from the pupil sample's first coordinate, which is then stretched back
over [0, 1) within the path's interval (one uniform number does both, independently).

A ghost ray's pupil point is drawn uniformly on a square of the exit-pupil plane that holds the whole
clear aperture of the last surface (`exit_pupil.exit_reach`), not in the direct path's pupil bound: a
ghost's rays may enter the lens where the direct path's are stopped. Its weight is that of
`PupilSampler.sample`: A·cos⁴θ/d².
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from solas_mi.errors import SolasError
from solas_mi.optics import ghost_paths
from solas_mi.optics.exit_pupil import exit_reach
from solas_mi.optics.lens import Lens
from solas_mi.psf.stray_light import ghosts

MODES = ("off", "on", "only")  # besides one path "j,i"
DIRECT_SHARE = 0.5  # the samples on the direct path with ghosts "on"
ENERGY_FLOOR = 0.25  # each ghost path's weight: its energy + this × the ghosts' mean energy
TABLE_RAYS = 48  # rays per side of the ghost table that sets the paths' probabilities


def parse(value, lens: Lens) -> list[tuple[int, int]] | None:
    """The ghost paths (j, i) 0-based of the lens file that `ghosts` `value` names (module docstring),
    None for "off"; SolasError for anything else."""
    text = str(value).strip().lower()
    if text == "off":
        return None
    every = ghost_paths.paths(lens)  # refuses an ideal thin lens
    if text in ("on", "only"):
        return every
    try:
        j, i = (int(v) - 1 for v in text.split(","))
    except ValueError:
        j = i = -1
    if (j, i) not in every:
        shown = ", ".join(f"{a + 1},{b + 1}" for a, b in every[:6])
        raise SolasError(
            f"lens_camera: ghosts {value!r} must be one of {', '.join(MODES)} or a path j,i of lens {lens.name} "
            f"(surfaces 1-based, reflect at j then at i < j, both changing the medium: {shown}, …)"
        )
    return [(j, i)]


class GhostSampler:
    """The paths of `ghosts` mode `value` through `lens` (module docstring) and their pupil sampling on the
    plane z = `plane_z` (mm) for film points at z = `image_z` up to `max_radius_mm` from the axis."""

    def __init__(self, lens: Lens, value, plane_z: float, max_radius_mm: float) -> None:
        self.mode = str(value)
        chosen = parse(value, lens)
        assert chosen is not None
        if len(chosen) > 1:
            table = {g.surfaces: g.energy for g in ghosts(lens, (0.0, 0.0), rays=TABLE_RAYS).ghosts}
            energy = np.array([table[(j + 1, i + 1)] for j, i in chosen])
            energy = energy + ENERGY_FLOOR * max(float(energy.mean()), 1e-300)
        else:
            energy = np.ones(1)
        share = DIRECT_SHARE if str(value).strip().lower() == "on" else 0.0
        n = len(lens.surfaces)
        # in the reversed lens that the camera traces, path (j, i) reflects first at n−1−i, then at n−1−j
        firsts = ([n] if share else []) + [n - 1 - i for j, i in chosen]
        seconds = ([n] if share else []) + [n - 1 - j for j, i in chosen]
        p = np.array(([share] if share else []) + list((1.0 - share) * energy / energy.sum()))
        self.direct = n
        self.bounds = np.cumsum(p)[:-1].tolist()  # the upper end of each path's interval but the last
        self.first, self.second = mi.UInt32(firsts), mi.UInt32(seconds)
        self.p, self.low = mi.Float(p), mi.Float(np.concatenate([[0.0], np.cumsum(p)[:-1]]))
        self.reach = exit_reach(lens, max_radius_mm)
        self.plane_z, self.image_z = plane_z, lens.image_z

    def choose(self, sample: mi.Point2f):
        """The path of each sample, from `sample.x`: (first, second, 1 / its probability, `sample` with its x
        stretched back over [0, 1))."""
        index = mi.UInt32(0)
        for bound in self.bounds:
            index += dr.select(sample.x >= bound, 1, 0)
        p, low = dr.gather(mi.Float, self.p, index), dr.gather(mi.Float, self.low, index)
        u = dr.clip((sample.x - low) / p, 0.0, 1.0 - 2**-24)
        first, second = dr.gather(mi.UInt32, self.first, index), dr.gather(mi.UInt32, self.second, index)
        return first, second, dr.rcp(p), mi.Point2f(u, sample.y)

    def target(self, film: mi.Point2f, sample: mi.Point2f, first, target: mi.Point2f, weight: mi.Float):
        """The pupil point and its weight of each sample: `target`, `weight` (the direct path's pupil
        sampling) where `first` is the direct path, else uniform on the square ±`reach`."""
        px, py = dr.fma(sample.x, 2.0 * self.reach, -self.reach), dr.fma(sample.y, 2.0 * self.reach, -self.reach)
        dz = self.plane_z - self.image_z
        cos4 = dr.square(dz * dz / (dr.square(px - film.x) + dr.square(py - film.y) + dz * dz))
        square = 4.0 * self.reach * self.reach * cos4 / (dz * dz)
        direct = first == self.direct
        return mi.Point2f(dr.select(direct, target.x, px), dr.select(direct, target.y, py)), dr.select(
            direct, weight, square
        )
