"""`lens_camera` (sensor): a real lens in front of any Mitsuba scene, traced sequentially inside the
sensor; the scene sees only the rays that leave the lens's first surface.

| parameter        | type      | unit        | default         | meaning                                            |
|------------------|-----------|-------------|-----------------|----------------------------------------------------|
| `lens`           | string    | —           | "solas-doublet" | shipped lens name or lens-file path                |
| `pitch_um`       | float     | µm          | 5.0             | pixel pitch                                        |
| `response`       | string    | —           | "srgb"          | camera response (`solas_mi.render.response.parse`) |
| `focus_distance` | float     | world units | the lens file's | object distance in focus, in front of surface 1 (inf: infinity) |
| `world_unit_mm`  | float     | mm          | 1000            | one world unit in mm (1000: the scene in metres)   |
| `fresnel`        | string    | —           | "off"           | "transmit": weight by each refraction's unpolarised|
|                  |           |             |                 | Fresnel transmittance; "off": lossless surfaces    |
| `to_world`       | transform | world units | identity        | the camera's frame: looks along local +z, +y up    |
| (film)           | film      | pixels      | hdrfilm 768×576 | its width and height: the sensor's columns, rows   |
| (sampler)        | sampler   | —           | independent, 4  | the samples per pixel                              |

`traverse` exposes `pitch_um`, `world_unit_mm` and `focus_distance` (world units; inf: infinity),
read-only (the pupil bounds and the image plane are built from them), and the film and sampler.

Geometry: the origin of `to_world` is the vertex of the lens's surface 1, the lens's axis its local
+z (`look_at` works as for `perspective`). The image is upright, as `perspective` renders it (row 0
up, column 0 on the camera's +x, its left): a `perspective` sensor with the same `to_world` and the
lens's field of view frames the same scene, seen from the lens's entrance pupil instead of its front
vertex. `focus_distance` focuses the lens as a unit: the whole lens moves against the sensor so that
an object that far in front of surface 1 is in focus (`solas_mi.optics.focus.focused`: the paraxial
image shift from the lens file's own object distance, whose image plane is the default).

Each sample takes one wavelength from the camera response (`solas_mi.render.response`), carried in
all four spectral lanes (with dispersion a path has one wavelength), a point in its pixel, and a
point inside the exit-pupil bound of that film position (`pupil_sampling.PupilSampler`, weight
A·cos⁴θ/d² as pbrt-v4's RealisticCamera). The ray is traced backward through the lens (image side
to object side) by the Float64 sequential tracer (`solas_mi.optics.tracer`, on the reversed lens of
`solas_mi.optics.exit_pupil`) in the Float64 type of the variant (Python floats in the scalar ones):
exact spheres and planes, Sellmeier n(λ) per path, every clear aperture and the stop clip, total
internal reflection ends the ray; a blocked ray has weight 0. The weight of `sample_ray` is the
pupil weight × 1/p(λ) × the Fresnel transmittance, scaled so that the pixel value is the image
irradiance in units of a lossless lens's on-axis irradiance from radiance 1: a uniform white scene
is 1 at the image centre (less with `fresnel` "transmit") and falls off with the lens's relative
illumination. `hdrfilm` develops a continuous response ("srgb", "table:") with Mitsuba's CIE tables;
lines ("lines", "mono:λ") have no density and need `specfilm`.

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

from solas_mi.errors import SolasError
from solas_mi.optics import tracer as T
from solas_mi.optics.exit_pupil import passes, reversed_lens
from solas_mi.optics.focus import focused
from solas_mi.optics.lens import Lens
from solas_mi.plugins.pupil_sampling import PupilSampler
from solas_mi.plugins.scene_files import load_lens, load_response
from solas_mi.plugins.wavelength_sampling import WavelengthSampler, lanes

FRESNEL = ("off", "transmit")


def _positive(props: mi.Properties, name: str, default: float, unit: str, infinite: bool = False) -> float:
    """A positive, finite (or, if `infinite`, also inf) float property (SolasError naming it otherwise)."""
    value = props.get(name, default)
    try:
        value = float(value)
    except (TypeError, ValueError):
        value = math.nan
    if not ((math.isfinite(value) or (infinite and value == math.inf)) and value > 0):
        raise SolasError(f"lens_camera: {name} {props.get(name)!r} must be a positive number ({unit})")
    return value


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
    return float((ok * cos4).sum() / (dz * dz) * (u1 - u0) * (v1 - v0) / grid ** 2)


class LensCamera(mi.Sensor):
    """The `lens_camera` sensor (parameters: the module docstring)."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        lens = load_lens(props)
        self.pitch_um = _positive(props, "pitch_um", 5.0, "µm")
        self.world_unit_mm = _positive(props, "world_unit_mm", 1000.0, "mm per world unit")
        self.fresnel = str(props.get("fresnel", "off"))
        if self.fresnel not in FRESNEL:
            raise SolasError(f"lens_camera: fresnel {self.fresnel!r} must be one of {', '.join(FRESNEL)}")
        if "focus_distance" in props:
            distance = _positive(props, "focus_distance", 1.0, "world units, in front of surface 1; inf", True)
            try:
                lens = focused(lens, distance * self.world_unit_mm)
            except SolasError as exc:
                raise SolasError(f"lens_camera: focus_distance {distance:g} (world units of {self.world_unit_mm:g} "
                                 f"mm): {exc}") from None
        self.lens = lens
        self.focus_distance = lens.object_distance / self.world_unit_mm
        self.response = load_response(props, lens, "srgb")
        self.pitch_mm = self.pitch_um * 1e-3
        self.width, self.height = (int(v) for v in self.film().size())
        self.crop_offset = [int(v) for v in self.film().crop_offset()]
        self.crop_size = [int(v) for v in self.film().crop_size()]
        half_diag = 0.5 * self.pitch_mm * math.hypot(self.width, self.height)
        r = self.response
        self.pupil = PupilSampler(lens, half_diag, sorted({float(r.lo_nm.min()), float(r.hi_nm.max()),
                                                           *lens.wavelengths_nm}))
        solid_angle = on_axis_solid_angle(lens, self.pupil, lens.primary_wavelength)
        if not solid_angle > 0:
            raise SolasError(f"lens_camera: no ray from the image centre passes lens {lens.name}")
        self.norm = 1.0 / solid_angle
        self.reversed = reversed_lens(lens)
        self.last_vertex_z = float(lens.vertex_z[-1])
        self.wavelengths = WavelengthSampler(r)

    def sample_wavelengths(self, si, sample, active=True):
        """One wavelength (nm) from the response in all four lanes (none in a mono variant), and its
        weight 1/p(λ)."""
        lam, index = self.wavelengths.sample(sample, active)
        return lanes(lam), mi.Spectrum(self.wavelengths.weight(index, active))

    def sample_ray(self, time, sample1, sample2, sample3, active=True):
        """The ray leaving surface 1 toward the scene (world units) and its weight (module docstring)."""
        lam, index = self.wavelengths.sample(sample1, active)
        inv_pdf = self.wavelengths.weight(index, active)
        # film point, lens frame (mm): row 0 at +y, column 0 at −x, the lens inverting the image;
        # Mitsuba's integrators pass sample2 in [0, 1]² over the film's crop window
        col = dr.fma(sample2.x, self.crop_size[0], self.crop_offset[0])
        row = dr.fma(sample2.y, self.crop_size[1], self.crop_offset[1])
        film = mi.Point2f((col - 0.5 * self.width) * self.pitch_mm, (0.5 * self.height - row) * self.pitch_mm)
        target, weight = self.pupil.sample(film, sample3, active)
        f64 = dr.float64_array_t(mi.Float)
        # the reversed lens: x, y kept, z mirrored; the film is its object, the pupil plane its z = 0
        rays = T.launch(self.reversed, None, None, f64(target.x), f64(target.y), (f64(film.x), f64(film.y)))
        traced = T.trace(self.reversed, rays, f64(lam) * 1e-3, fresnel=self.fresnel == "transmit")
        out = traced.rays
        passed = traced.ok & (traced.clipped_by == 0)
        # camera frame (x, −y, −z of the lens frame): looks along +z, upright; surface 1 at the origin
        scale = 1.0 / self.world_unit_mm
        origin = mi.Point3f(mi.Float(out.x * scale), mi.Float(-out.y * scale),
                            mi.Float((out.z - self.last_vertex_z) * scale))
        direction = mi.Vector3f(mi.Float(out.dx), mi.Float(-out.dy), mi.Float(out.dz))
        # origin and direction apart: `transform @ ray` fails in a mono variant once a spectral one ran (Mitsuba 3.9)
        to_world = self.world_transform()
        ray = mi.Ray3f(to_world @ origin, to_world @ direction, time, lanes(lam))
        weight = weight * self.norm * mi.Float(traced.transmittance)
        weight = dr.select(active & mi.Bool(passed), weight, 0.0)
        return ray, mi.Spectrum(weight * inv_pdf)

    def sample_ray_differential(self, time, sample1, sample2, sample3, active=True):
        ray, weight = self.sample_ray(time, sample1, sample2, sample3, active)
        return mi.RayDifferential3f(ray), weight

    def sample_direction(self, it, sample, active=True):
        raise SolasError("lens_camera: light tracing cannot connect to a sensor behind a lens; use an "
                         "integrator that starts paths at the camera (path, volpath, aov, direct)")

    def pdf_direction(self, it, ds, active=True):
        return self.sample_direction(it, None, active)

    def eval_direction(self, it, ds, active=True):
        return self.sample_direction(it, None, active)

    def sample_position(self, time, sample, active=True):
        return self.sample_direction(None, None, active)

    def eval(self, si, active=True):
        return mi.Spectrum(0.0)  # the camera emits nothing and cannot be hit

    def bbox(self):
        """The lens and film, in world units."""
        reach = max(max(s.semi_diameter for s in self.lens.surfaces),
                    0.5 * self.pitch_mm * max(self.width, self.height))
        corners = np.array([[sx * reach, sy * reach, sz * self.lens.image_z, self.world_unit_mm]
                            for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 0)]) / self.world_unit_mm
        world = corners @ np.array(self.world_transform().matrix, dtype=np.float64).reshape(4, 4).T
        return mi.ScalarBoundingBox3f(world[:, :3].min(axis=0), world[:, :3].max(axis=0))

    def traverse(self, callback) -> None:
        super().traverse(callback)
        callback.put("pitch_um", self.pitch_um, mi.ParamFlags.ReadOnly)
        callback.put("world_unit_mm", self.world_unit_mm, mi.ParamFlags.ReadOnly)
        callback.put("focus_distance", self.focus_distance, mi.ParamFlags.ReadOnly)

    def to_string(self) -> str:
        return (f"LensCamera[{self.lens.name}, {self.width}x{self.height} px of {self.pitch_um:g} um, "
                f"focus {self.focus_distance:g}, response {self.response.name}, fresnel {self.fresnel}]")


def register() -> None:
    mi.register_sensor("lens_camera", LensCamera)  # this variant's class, bound now
