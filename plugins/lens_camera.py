"""`lens_camera` (sensor): a real lens in front of any Mitsuba scene, traced sequentially inside the
sensor; the scene sees only the rays that leave the lens's first surface.

| parameter        | type      | unit        | default         | meaning                                            |
|------------------|-----------|-------------|-----------------|----------------------------------------------------|
| `lens`           | string    | —           | "solas-doublet" | shipped lens name or lens-file path                |
| `pitch_um`       | float     | µm          | the film spans  | pixel pitch; default: the film's width spans the   |
|                  |           |             | the lens's field| lens's ±field_deg (a fisheye: its image diameter), |
|                  |           |             |                 | as `render-image` frames it; logged (Info) and     |
|                  |           |             |                 | said by `to_string`; a lens without either refused |
| `response`       | string    | —           | "srgb"          | camera response (`solas_mi.render.response.parse`) |
| `focus_distance` | float     | world units | the lens file's | object distance in focus, in front of surface 1 (inf: infinity) |
| `world_unit_mm`  | float     | mm          | 1000            | one world unit in mm (1000: the scene in metres)   |
| `fresnel`        | string    | —           | "off"           | "transmit": weight by each refraction's unpolarised|
|                  |           |             | ("transmit"     | Fresnel transmittance (a coated surface's: its     |
|                  |           |             | with `ghosts`)  | coating's); "off": lossless surfaces               |
| `ghosts`         | string    | —           | "off"           | the lens's ghosts (`ghost_sampling`): "on" (the    |
|                  |           |             |                 | direct path and every two-reflection path), "only" |
|                  |           |             |                 | (the stray light alone), "j,i" (that ghost alone); |
|                  |           |             |                 | "off": the direct image, traced as without it      |
| `to_world`       | transform | world units | identity        | the camera's frame: looks along local +z, +y up    |
| `stratify_wavelengths` | boolean | —     | true            | stratify the wavelengths of a pixel's samples      |
| `lane_tolerance` | float     | pixels      | 0.25            | ε: how alike the spectral lanes' rays must leave   |
|                  |           |             |                 | the lens to share a path (0: never)                |
| (film)           | film      | pixels      | hdrfilm 768×576 | its width and height: the sensor's columns, rows;  |
|                  |           |             |                 | its crop window (`crop_offset_x`, …): those drawn  |
| (sampler)        | sampler   | —           | independent, 4  | the samples per pixel                              |

`traverse` exposes `pitch_um`, `world_unit_mm` and `focus_distance` (world units; inf: infinity),
read-only (the pupil bounds and the image plane are built from them), the film and sampler, and
`to_world`, updatable: a moving camera's frames render without reloading the scene.
The lens, response, film (and its crop window), pupil and wavelengths are `lens_film.LensFilm`'s,
shared with `lens_sensor`.

Geometry: the origin of `to_world` is the vertex of the lens's surface 1, the lens's axis its local
+z (`look_at` works as for `perspective`). The image is upright, as `perspective` renders it (row 0
up, column 0 on the camera's +x, its left): a `perspective` sensor with the same `to_world` and the
lens's field of view frames the same scene, seen from the lens's entrance pupil instead of its front
vertex. `focus_distance` focuses the lens as a unit: the whole lens moves against the sensor so that
an object that far in front of surface 1 is in focus (`solas_mi.optics.focus.focused`: the paraxial
image shift from the lens file's own object distance, whose image plane is the default).

How a sample is traced (why: [the lens camera's colour
noise](../details/render.md#colour-noise-of-the-lens-camera)): a point in its pixel and a point inside
the exit-pupil bound of that film position (`pupil_sampling.PupilSampler`, weight A·cos⁴θ/d² as
pbrt-v4's RealisticCamera); four wavelengths from the camera response (`solas_mi.render.response`), one
per spectral lane, lane i in the i-th quarter of the response's distribution
(`WavelengthSampler.sample_quantile`), and a hero lane whose sample is stratified per pixel
(`stratified`). All four lanes are traced backward through the lens (image side to object side) by the
Float64 sequential tracer (`solas_mi.optics.tracer`, on the reversed lens of
`solas_mi.optics.exit_pupil`): exact spheres and planes, Sellmeier n(λ) per lane, every clear aperture
and the stop clip, total internal reflection ends the ray. The hero's ray leaves for the scene carrying
the lanes that leave the lens within `lane_tolerance` of it (`lanes_together`), each weighted 4/(the
lanes alike it), so every lane's estimate is unbiased.

With `ghosts`, each sample first draws its path, the direct one or a ghost (`ghost_sampling`: by the
ghost table's energies, or toward the scene's area emitters, `ghost_guide`), and all its lanes follow it (`solas_mi.optics.ghost_trace`: the reversed lens's
surfaces met from either side, reflected or crossed; every event weighs the ray by its coating's or
Fresnel's reflectance or transmittance); the weight is divided by the path's probability. A ghost's pupil
point is drawn on a square that holds the last surface's whole clear aperture (its rays may enter where
the direct path's are stopped), toward the scene's area emitters where it has any.

The weight of `sample_ray` is the pupil weight × 1/p(λ) × the Fresnel transmittance, scaled so that the
pixel value is the image irradiance in units of a lossless lens's on-axis irradiance from radiance 1: a
uniform white scene is 1 at the image centre (less with `fresnel` "transmit") and falls off with the
lens's relative illumination. `hdrfilm` develops a continuous response ("srgb", "table:") with
Mitsuba's CIE tables; lines ("lines", "mono:λ") have no density and need `specfilm`: "lines" under an
`hdrfilm` of a spectral variant is refused (SolasError naming both ways out). Rays blocked by the lens
(past the image circle, at a stop, by total internal reflection) leave the vertex along the axis with
weight 0 and `maxt` 0: every ray is finite, and the scene traces no path for them (an `aov` integrator
reads them as misses).

Variants: spectral, or mono for a response of one wavelength (mono:λ): the lens is traced at λ and
the scene's RGB and spectral data become Mitsuba's luminance, so a mono render equals the spectral
one at λ only in a scene of grey (flat) spectra (`solas_mi.render.mitsuba.variant_for`). A mono
variant with a response of more wavelengths is refused (SolasError naming both).

Integrators: any that starts paths at the camera (`path`, `volpath`, `aov`, `direct`, …). Light
tracing (`ptracer`) cannot connect to a sensor behind a lens: `sample_direction`, `pdf_direction`,
`eval_direction` and `sample_position` raise a SolasError.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np
from solas_mi.plugins.ghost_sampling import GhostSampler
from solas_mi.plugins.lens_film import LensFilm, positive
from solas_mi.plugins.pupil_sampling import PupilSampler
from solas_mi.plugins.scene_probe import calling_render
from solas_mi.plugins.wavelength_sampling import lanes

from solas_mi.errors import SolasError
from solas_mi.optics import ghost_trace, tracer, virtual_object
from solas_mi.optics.exit_pupil import passes, reversed_lens
from solas_mi.optics.focus import focused
from solas_mi.optics.lens import Lens
from solas_mi.optics.paraxial import paraxial

FRESNEL = ("off", "transmit")


def select_lane(values: list, lane):
    """values[lane] per ray: `lane` an index array of 0…3 over a list of four values."""
    return dr.select(lane == 0, values[0], dr.select(lane == 1, values[1], dr.select(lane == 2, values[2], values[3])))


def on_axis_solid_angle(lens: Lens, sampler: PupilSampler, wavelength_nm: float, grid: int = 512) -> float:
    """∫ cos⁴θ/d² dA over the exit pupil seen from the film centre, for passing rays (sr): a lossless
    lens's on-axis image irradiance under radiance 1."""
    u0, u1, v0, v1 = sampler.bounds.at(np.array(0.0))[:4]
    u = u0 + (np.arange(grid) + 0.5) / grid * (u1 - u0)
    v = v0 + (np.arange(grid) + 0.5) / grid * (v1 - v0)
    gu, gv = (a.ravel() for a in np.meshgrid(u, v))
    ok = passes(reversed_lens(lens), np.zeros(len(gu)), 0.0, gu, gv, wavelength_nm)
    dz = sampler.plane_z - sampler.image_z
    cos4 = (dz * dz / (gu * gu + gv * gv + dz * dz)) ** 2
    return float((ok * cos4).sum() / (dz * dz) * (u1 - u0) * (v1 - v0) / grid**2)


class LensCamera(LensFilm):
    """The `lens_camera` sensor (parameters: the module docstring; the film, lens, response, pupil and
    wavelengths: `lens_film.LensFilm`)."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(
            props, "lens_camera", "srgb", "an integrator that starts paths at the camera (path, volpath, aov, direct)"
        )
        self.check_film()
        self.stratify = bool(props.get("stratify_wavelengths", True))
        ghosts = str(props.get("ghosts", "off")).strip().lower()
        self.fresnel = str(props.get("fresnel", "off" if ghosts == "off" else "transmit"))
        if self.fresnel not in FRESNEL:
            raise SolasError(f"lens_camera: fresnel {self.fresnel!r} must be one of {', '.join(FRESNEL)}")
        self.ghosts = None if ghosts == "off" else self.ghost_sampler(ghosts)
        self.focus_distance = self.lens.object_distance / self.world_unit_mm
        solid_angle = on_axis_solid_angle(self.lens, self.pupil, self.lens.primary_wavelength)
        if not solid_angle > 0:
            raise SolasError(f"lens_camera: no ray from the image centre passes lens {self.lens.name}")
        self.norm = 1.0 / solid_angle
        self.reversed = reversed_lens(self.lens)
        self.last_vertex_z = float(self.lens.vertex_z[-1])
        self.lane_tolerances(props)

    def ghost_sampler(self, ghosts: str) -> GhostSampler:
        """The sampler of the paths of `ghosts` (`ghost_sampling`); SolasError where they cannot be traced:
        `fresnel` "off" (lossless surfaces reflect nothing), a scalar variant (one ray at a time)."""
        if self.fresnel == "off":
            raise SolasError(
                f"lens_camera: ghosts {ghosts!r} need the surfaces' reflectance and transmittance: fresnel 'off' "
                "(lossless surfaces) reflects nothing; leave fresnel out or give 'transmit'"
            )
        if not dr.is_jit_v(mi.Float):
            raise SolasError(f"lens_camera: ghosts need a JIT variant (llvm_ad_*, cuda_ad_*), not {mi.variant()}")
        sampler = GhostSampler(self.lens, ghosts, self.pupil.plane_z, (self.film_size, self.pitch_mm))
        if all(s.coating is None for s in self.lens.surfaces):
            mi.Log(mi.LogLevel.Warn, f"lens_camera: lens {self.lens.name} has no coatings: its ghosts are bare glass's")
        return sampler

    def lane_tolerances(self, props: mi.Properties) -> None:
        """Where the lanes share a path (docs/details/render.md, "Colour noise of the lens camera"): rays at
        the response's shortest and longest wavelengths leave the lens within ε α in direction plus origin
        over the focus distance, and within ε D/2 in origin."""
        try:
            eps = float(props.get("lane_tolerance", 0.25))
        except (TypeError, ValueError):
            eps = math.nan
        if not eps >= 0:
            raise SolasError(
                f"lens_camera: lane_tolerance {props.get('lane_tolerance')!r} must be a number >= 0 "
                "(a fraction of a pixel's angular footprint; 0: every path the hero lane's)"
            )
        self.lane_tolerance = eps
        first_order = paraxial(self.lens)
        self.angle_tolerance = eps * self.pitch_mm / abs(first_order.efl_mm)
        self.origin_tolerance = 0.5 * eps * first_order.entrance_pupil_diameter_mm / self.world_unit_mm
        self.inv_focus = 0.0 if math.isinf(self.focus_distance) else 1.0 / self.focus_distance

    def lanes_together(self, origins, directions, passed) -> list[list]:
        """`together[i][j]`: lanes i and j both passed and leave the lens within `lane_tolerance` of each
        other (the bound: docs/details/render.md, "Colour noise of the lens camera"; symmetric, and a passed
        lane is alike itself)."""
        together = [[passed[i] if i == j else None for j in range(4)] for i in range(4)]
        for i in range(4):
            for j in range(i + 1, 4):
                gap = dr.norm(origins[i] - origins[j])
                together[i][j] = together[j][i] = (
                    passed[i]
                    & passed[j]
                    & (gap <= self.origin_tolerance)
                    & (dr.norm(directions[i] - directions[j]) + gap * self.inv_focus <= self.angle_tolerance)
                )
        return together

    def check_film(self) -> None:
        """SolasError for lines (no density) under an `hdrfilm` of a spectral variant: the film would
        develop them with the CIE observer as if they were a continuous spectrum (nearly black)."""
        response = self.response
        if (
            mi.is_spectral
            and self.film().class_name() == "HDRFilm"
            and bool((response.hi_nm == response.lo_nm).any())
            and response.single_wavelength is None
        ):
            raise SolasError(
                f"lens_camera: response {response.name!r} has lines, which an hdrfilm cannot develop "
                "(they have no spectral density); use a specfilm with one sensitivity per line, or a "
                "continuous response (srgb, table:<file.csv>)"
            )

    def prepared(self, lens: Lens, props: mi.Properties) -> Lens:
        """The lens focused at `focus_distance` (world units of `world_unit_mm`), if given."""
        self.world_unit_mm = positive(props, "world_unit_mm", 1000.0, "mm per world unit", "lens_camera")
        if "focus_distance" not in props:
            virtual_object.check_real(
                lens,
                "lens_camera",
                "give focus_distance to focus it on the scene, or trace it instead (lens info, psf)",
            )
            return lens
        distance = positive(
            props, "focus_distance", 1.0, "world units, in front of surface 1; inf", "lens_camera", True
        )
        try:
            return focused(lens, distance * self.world_unit_mm)
        except SolasError as exc:
            raise SolasError(
                f"lens_camera: focus_distance {distance:g} (world units of {self.world_unit_mm:g} mm): {exc}"
            ) from None

    def stratified(self, sample1, sample2):
        """The wavelength sample of the k-th of a pixel's n samples moved into the k-th of n strata,
        (k + sample1)/n, where the wavefront is Mitsuba's (`SamplingIntegrator`: sample i of the
        wavefront is sample i mod n of pixel i div n, row-major over the crop window;
        `samples_in_pixel_order`); else `sample1` unchanged (scalar variants, a symbolic scope, any
        other layout, `stratify_wavelengths` false). Either way each wavelength sample is uniform: an
        unbiased estimate."""
        pixels = self.width * self.height
        n = dr.width(sample1) // pixels if dr.is_jit_v(mi.Float) and self.stratify else 0
        if (
            n < 2
            or n * pixels != dr.width(sample1)
            or dr.width(sample2) != n * pixels
            or dr.flag(dr.JitFlag.SymbolicScope)
        ):
            return sample1
        count = dr.opaque(mi.UInt32, n)  # one kernel for every spp
        i = dr.arange(mi.UInt32, n * pixels)
        pixel = i // count
        if not self.samples_in_pixel_order(pixel, sample2):
            return sample1
        return (mi.Float(i - pixel * count) + dr.clip(sample1, 0.0, 1.0 - 2**-24)) / mi.Float(count)

    def samples_in_pixel_order(self, pixel, sample2) -> bool:
        """Whether the film samples `sample2` lie in the pixels `pixel` (row-major over the crop window):
        taken as true for Mitsuba's own integrators (C++, and Python ones of `mitsuba.ad`: all lay out
        the wavefront so, `sample_rays`) on a film without a border, else checked on the values (an
        evaluation, which splits the render's kernel)."""
        if self.film().sample_border():
            return False
        _, integrator = calling_render()
        if integrator is not None and type(integrator).__module__.startswith("mitsuba"):
            return True
        col, row = mi.Float(pixel % self.width), mi.Float(pixel // self.width)
        x, y = sample2.x * self.width, sample2.y * self.height
        return bool(dr.all((x >= col - 1e-3) & (x <= col + 1.001) & (y >= row - 1e-3) & (y <= row + 1.001)))

    def exit_ray(self, film, target, lam, path=None):
        """The ray from film point `film` toward pupil point `target` (mm) at wavelength(s) `lam` (nm),
        traced through the lens (along `path`, (first, second) of `ghost_trace`, where given): its origin
        on surface 1 and direction in the camera frame (world units), whether it passed, and its Fresnel
        transmittance (a ghost's: its reflectances too). A blocked ray (past the image circle, TIR) may
        hold NaN: it leaves from the vertex along the axis, so that no integrator multiplies its weight 0
        by a NaN radiance."""
        f64 = dr.float64_array_t(mi.Float)
        # the reversed lens: x, y kept, z mirrored; the film is its object, the pupil plane its z = 0
        rays = tracer.launch(self.reversed, None, None, f64(target.x), f64(target.y), (f64(film.x), f64(film.y)))
        if path is None:
            result = tracer.trace(self.reversed, rays, f64(lam) * 1e-3, fresnel=self.fresnel == "transmit")
            leaving, passed, transmittance = result.rays, result.ok & (result.clipped_by == 0), result.transmittance
        else:
            leaving, passed, transmittance = ghost_trace.trace_paths(self.reversed, rays, f64(lam) * 1e-3, *path)
        # camera frame (x, −y, −z of the lens frame): looks along +z, upright; surface 1 at the origin
        scale = 1.0 / self.world_unit_mm
        origin = mi.Point3f(
            mi.Float(leaving.x * scale),
            mi.Float(-leaving.y * scale),
            mi.Float((leaving.z - self.last_vertex_z) * scale),
        )
        direction = mi.Vector3f(mi.Float(leaving.dx), mi.Float(-leaving.dy), mi.Float(leaving.dz))
        passed = mi.Bool(passed) & dr.all(dr.isfinite(origin)) & dr.all(dr.isfinite(direction))
        origin = dr.select(passed, origin, mi.Point3f(0.0))
        direction = dr.select(passed, direction, mi.Vector3f(0.0, 0.0, 1.0))
        return origin, direction, passed, mi.Float(transmittance)

    def lane_samples(self, sample1, sample2):
        """The lanes' samples of the response's distribution, and the hero lane (module docstring): the
        hero's `stratified` sample t, its quarter h = ⌊4t⌋, and the other lanes i at (4t − h + i)/4;
        one lane, `sample1`, in a mono variant."""
        if not mi.is_spectral:
            return [sample1], 0
        t = self.stratified(sample1, sample2)
        hero = dr.minimum(mi.UInt32(t * 4.0), 3)
        base = dr.fma(mi.Float(hero), -0.25, t) * 4.0
        return [dr.select(hero == i, t, (base + i) * 0.25) for i in range(4)], hero

    def sample_ray(self, time, sample1, sample2, sample3, active=True):
        """The ray leaving surface 1 toward the scene (world units) and its weight (module docstring):
        the four lanes traced from one film point and pupil point, the hero's ray carrying those that
        leave the lens alike it."""
        film, path = self.film_point(sample2), None
        if self.ghosts is not None:  # the sample's path and pupil point (`ghost_sampling`)
            if not dr.flag(dr.JitFlag.SymbolicScope):  # toward the scene's bright emitters (`ghost_guide`)
                matrix = np.array(self.world_transform().matrix, dtype=np.float64).reshape(4, 4)
                wavelength = self.response.single_wavelength or self.lens.primary_wavelength
                self.ghosts.aim(calling_render()[0], matrix, wavelength)
            path, direct, sample3, point, ghost_weight = self.ghosts.draw(film, sample3)
        target, weight = self.pupil.sample(film, sample3, active)
        if path:
            target, weight = self.ghosts.target(direct, target, weight, point, ghost_weight)
        samples, hero = self.lane_samples(sample1, sample2)
        lams, origins, directions, passed, weights = [], [], [], [], []
        for sample in samples:
            lam, inverse_pdf = self.wavelengths.sample_quantile(sample, active)
            origin, direction, ok, transmittance = self.exit_ray(film, target, lam, path)
            for values, value in zip((lams, origins, directions, passed), (lam, origin, direction, ok)):
                values.append(value)
            w = weight * self.norm * transmittance * inverse_pdf
            weights.append(dr.select(active & ok, w, 0.0))
        if mi.is_spectral:  # lane i carried where alike the hero, weighted 4 / (the lanes alike lane i)
            together = self.lanes_together(origins, directions, passed)
            counts = [dr.maximum(sum(dr.select(x, 1.0, 0.0) for x in row), 1.0) for row in together]
            weights = [
                dr.select(select_lane(together[i], hero), 4.0 * w / counts[i], 0.0) for i, w in enumerate(weights)
            ]
            origins, directions = [select_lane(origins, hero)], [select_lane(directions, hero)]
        # origin and direction apart: `transform @ ray` fails in a mono variant once a spectral one ran (Mitsuba 3.9)
        to_world = self.world_transform()
        ray = mi.Ray3f(
            to_world @ origins[0],
            to_world @ directions[0],
            time,
            mi.Spectrum(*lams) if mi.is_spectral else lanes(lams[0]),
        )
        # a blocked hero carries no lane (`lanes_together`): its path would add 0, so it meets nothing
        ray.maxt = dr.select(select_lane(passed, hero) if mi.is_spectral else passed[0], ray.maxt, 0.0)
        return ray, mi.Spectrum(*weights) if mi.is_spectral else mi.Spectrum(weights[0])

    def sample_position(self, time, sample, active=True):
        return self.sample_direction(None, None, active)

    def bbox(self):
        """The lens and film, in world units."""
        reach = max(max(s.semi_diameter for s in self.lens.surfaces), *self.film_half_mm)
        corners = (
            np.array(
                [
                    [sx * reach, sy * reach, sz * self.lens.image_z, self.world_unit_mm]
                    for sx in (-1, 1)
                    for sy in (-1, 1)
                    for sz in (-1, 0)
                ]
            )
            / self.world_unit_mm
        )
        world = corners @ np.array(self.world_transform().matrix, dtype=np.float64).reshape(4, 4).T
        return mi.ScalarBoundingBox3f(world[:, :3].min(axis=0), world[:, :3].max(axis=0))

    def traverse(self, callback) -> None:
        super().traverse(callback)
        callback.put("world_unit_mm", self.world_unit_mm, mi.ParamFlags.ReadOnly)
        callback.put("focus_distance", self.focus_distance, mi.ParamFlags.ReadOnly)
        callback.put("to_world", self.m_to_world, mi.ParamFlags.NonDifferentiable)

    def to_string(self) -> str:
        extra = () if self.ghosts is None else (f"ghosts {self.ghosts.mode}",)
        return self.describe(f"focus {self.focus_distance:g}", f"fresnel {self.fresnel}", *extra)


def register() -> None:
    mi.register_sensor("lens_camera", LensCamera)  # this variant's class, bound now
