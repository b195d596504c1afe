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

A ghost ray's pupil point is drawn on a square of the exit-pupil plane that holds the whole clear aperture
of the last surface (`exit_pupil.exit_reach`), not in the direct path's pupil bound: a ghost's rays may
enter the lens where the direct path's are stopped. Uniformly on it (path by `PathChoice`) where the scene
has no area emitter in front of the lens; else (`aim`, once per scene and camera placement) path and point
together from the film tile's histogram of the emitters' light traced forward (`ghost_guide`), mixed with
the uniform choice. Its weight is cos⁴θ/d² over the density of its path and point (on the square, uniform:
A·cos⁴θ/d²/p, as `PupilSampler.sample`).
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np
from solas_mi.plugins.ghost_guide import GhostGuide, bright_emitters, crossings

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


class PathChoice:
    """Ghost paths drawn with probabilities ∝ `energy` + `ENERGY_FLOOR` × its mean (module docstring)."""

    def __init__(self, energy: np.ndarray) -> None:
        energy = energy + ENERGY_FLOOR * max(float(energy.mean()), 1e-300)
        p = energy / energy.sum()
        self.bounds = np.cumsum(p)[:-1].tolist()  # the upper end of each path's interval but the last
        self.p, self.low = mi.Float(p), mi.Float(np.concatenate([[0.0], np.cumsum(p)[:-1]]))

    def choose(self, u: mi.Float):
        """The path drawn by uniform `u`: (its index, its probability, `u` stretched back over [0, 1))."""
        index = mi.UInt32(0)
        for bound in self.bounds:
            index += dr.select(u >= bound, 1, 0)
        p, low = self.probability(index), dr.gather(mi.Float, self.low, index)
        return index, p, dr.clip((u - low) / p, 0.0, 1.0 - 2**-24)

    def probability(self, index) -> mi.Float:
        return dr.gather(mi.Float, self.p, index)


class GhostSampler:
    """The paths of `ghosts` mode `value` through `lens` (module docstring) and their pupil sampling on the
    plane z = `plane_z` (mm) for the film `film` (its (columns, rows), its pitch in mm)."""

    def __init__(self, lens: Lens, value, plane_z: float, film) -> None:
        self.mode, self.lens = str(value), lens
        self.chosen = parse(value, lens)
        assert self.chosen is not None
        if len(self.chosen) > 1:
            table = {g.surfaces: g.energy for g in ghosts(lens, (0.0, 0.0), rays=TABLE_RAYS).ghosts}
            self.energy = np.array([table[(j + 1, i + 1)] for j, i in self.chosen])
        else:
            self.energy = np.ones(1)
        self.paths = PathChoice(self.energy)
        self.share = DIRECT_SHARE if self.mode.strip().lower() == "on" else 0.0
        n = len(lens.surfaces)
        # in the reversed lens that the camera traces, path (j, i) reflects first at n−1−i, then at n−1−j
        self.first = mi.UInt32([n - 1 - i for j, i in self.chosen] + [n])  # the direct path last
        self.second = mi.UInt32([n - 1 - j for j, i in self.chosen] + [n])
        self.film_size, self.pitch_mm = film
        self.reach = exit_reach(lens, math.hypot(*self.film_size) * 0.5 * self.pitch_mm)
        self.plane_z, self.image_z = plane_z, lens.image_z
        self.guide, self.aimed_at = None, None

    def aim(self, scene, to_world: np.ndarray, wavelength_nm: float) -> None:
        """Guide the ghosts' pupil points toward the bright emitters of `scene` (`ghost_guide`), seen by a
        camera at 4×4 `to_world`; once per scene and camera placement. Where a guide finds light on the film,
        the paths' probabilities outside it follow the table's energy and the guide's flux, half each."""
        key = (id(scene), to_world.tobytes())
        if scene is None or key == self.aimed_at:
            return
        self.aimed_at, self.guide = key, None
        emitters = bright_emitters(scene, to_world)
        planes = (self.image_z, self.plane_z)
        hits = crossings(self.lens, self.chosen, emitters, wavelength_nm, planes) if emitters else None
        if hits is None:
            return
        self.guide = GhostGuide(hits, len(self.chosen), self.film_size, self.pitch_mm, self.reach)
        flux = self.guide.flux
        if flux.sum() > 0:
            self.paths = PathChoice(0.5 * self.energy / self.energy.sum() + 0.5 * flux / flux.sum())

    def draw(self, film: mi.Point2f, sample: mi.Point2f):
        """Each sample's path and, for a ghost, its pupil point and weight: ((first, second) of `ghost_trace`,
        whether it is the direct path, `sample` stretched back over [0, 1)² for the direct path's pupil
        sampling, the ghost's pupil point, its weight cos⁴θ/d² over the density of path and point)."""
        u = sample.x
        direct = (u < self.share) if self.share else mi.Bool(False)
        if self.share:
            u = dr.clip(dr.select(direct, u / self.share, (u - self.share) / (1.0 - self.share)), 0.0, 1.0 - 2**-24)
        if self.guide is None:
            index, p, v = self.paths.choose(u)
            point = mi.Point2f(
                dr.fma(v, 2.0 * self.reach, -self.reach), dr.fma(sample.y, 2.0 * self.reach, -self.reach)
            )
            density = p / (4.0 * self.reach * self.reach)
        else:
            index, point, density = self.guide.sample(film, mi.Point2f(u, sample.y), self.paths)
        index = dr.select(direct, len(self.chosen), index)
        dz = self.plane_z - self.image_z
        cos4 = dr.square(dz * dz / (dr.square(point.x - film.x) + dr.square(point.y - film.y) + dz * dz))
        weight = cos4 / (dz * dz * density * (1.0 - self.share))
        path = dr.gather(mi.UInt32, self.first, index), dr.gather(mi.UInt32, self.second, index)
        return path, direct, mi.Point2f(u, sample.y), point, weight

    def target(self, direct, target: mi.Point2f, weight: mi.Float, point: mi.Point2f, ghost_weight: mi.Float):
        """The pupil point and weight of each sample: the direct path's pupil sampling (`target`, `weight`
        over the direct path's probability) on the direct path, else the ghost's."""
        if not self.share:
            return point, ghost_weight
        return mi.Point2f(dr.select(direct, target.x, point.x), dr.select(direct, target.y, point.y)), dr.select(
            direct, weight / self.share, ghost_weight
        )
