"""`lens_sensor` (sensor): a film on a lens's image plane that looks through the lens.

| parameter  | type    | unit    | default          | meaning                                                |
|------------|---------|---------|------------------|--------------------------------------------------------|
| `lens`     | string  | —       | "solas-doublet"  | shipped lens name or lens-file path                    |
| `pitch_um` | float   | µm      | the film spans   | pixel pitch; default: the film's width spans ±`fov_deg`|
|            |         |         | ±`fov_deg`       | (a fisheye: its image diameter), logged (Info)         |
| `fov_deg`  | float   | degrees | the lens's field | half the horizontal field the input image spans        |
| `response` | string  | —       | "lines"          | camera response (`solas_mi.render.response.parse`)     |
| (film)     | film    | pixels  | hdrfilm 768×576  | its width and height are the sensor's columns and rows;|
|            |         |         |                  | its crop window (`crop_offset_x`, …): the pixels drawn |
| (sampler)  | sampler | —       | independent, 4   | its sample_count is `solas-mi render`'s default spp    |

`traverse` exposes `pitch_um` and `fov_deg`, read-only (the exit-pupil bounds and the irradiance
scale are built from them), and the film and sampler as children. `pitch_um` must be a positive
number (SolasError naming it otherwise).

The lens, response, film (and its crop window: a cropped render is exactly those pixels of the whole
one), pupil and wavelengths are `lens_film.LensFilm`'s, shared with `lens_camera`.

`lens` goes through Mitsuba's file resolver first; the lens must be focused at infinity (a near
object is `image_object`'s `distance_mm`). `fov_deg` sets the ideal camera's pinhole focal length (a lens of polar fields, a fisheye, uses its
paraxial focal length instead).
`response` is "lines" (the lens's design wavelengths), "lines:λ,…", "srgb", "mono:λ" (λ in nm) or
"table:FILE.csv".

Films: solas-mi's loop (`solas_mi.render.loop`) develops pixels itself with the response's channel
weights and ignores the film's other settings. Mitsuba's own integrators develop through the film,
with the sample weight of `sample_ray` = the pupil weight below × 1/p(λ) (`sample_wavelengths`: p is
the response's density in nm⁻¹, or a line's probability): `hdrfilm` then converts a continuous
response ("srgb", "table:") with Mitsuba's CIE 1931 tables over the response's range (srgb: 380–780
nm), as the "srgb" response does in the loop (README "Colour"), and `specfilm` with one
sensitivity per line, zero at the other lines, returns each line's value for "lines" and "mono"
(lines have no density: `hdrfilm` cannot integrate them).

Integrators: the sensor sees the scene only through the lens, so Mitsuba's `path`, `volpath` and
`aov` render it (and solas-mi's loop); others (`direct`, `ptracer`, …) stop with a SolasError naming
them when the render starts (`plugins/scene_probe.py` finds the integrator). Light tracing cannot
connect to it: `sample_direction`, `pdf_direction` and `eval_direction` raise.

Each sample takes a point in its pixel and a point inside the exit-pupil bound of that film
position (`solas_mi.optics.exit_pupil`; nothing assumes the stop is the last surface), and one
wavelength drawn from the camera response (`solas_mi.render.response`), carried in all four spectral
lanes: with dispersion a path has one wavelength. A ray from film point x toward a point of the bound
(area A, on a plane a distance d from the film) weighs A·cos⁴θ/d², θ its angle to the axis, as in
pbrt-v4's RealisticCamera (M. Pharr, W. Jakob, G. Humphreys, "Physically Based Rendering: From
Theory to Implementation", 4th ed., MIT Press, 2023). The weight is scaled so that the pixel value is
the mean image irradiance over the pixel in units of the ideal camera's
(`solas_mi.optics.illumination.ideal_irradiance`, with the pinhole focal length of
`solas_mi.optics.camera` for an input spanning ±fov_deg): an ideal lossless lens returns the input
image.

Variants: spectral, or mono for a response of one wavelength (the lens geometry then refracts at
`sellmeier_dielectric`'s `wavelength` and the object takes `image_object`'s, which solas-mi's scenes
set to the response's; solas-mi's loop checks that they agree). A mono variant with a response of
more wavelengths is refused (SolasError naming both).

Coordinates are the lens file's (mm): surface 1's vertex at the origin, +z toward the image, +y up;
film row 0 is +y.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np
from solas_mi.plugins.lens_film import LensFilm
from solas_mi.plugins.scene_probe import calling_render, integrator_name
from solas_mi.plugins.tables import lookup, table, zeros
from solas_mi.plugins.wavelength_sampling import lanes

from solas_mi.errors import SolasError
from solas_mi.optics.camera import pinhole_focal_mm
from solas_mi.optics.illumination import ideal_irradiance, image_scales
from solas_mi.optics.lens import Lens
from solas_mi.optics.paraxial import paraxial

INTEGRATORS = ("path", "volpath", "aov")  # Mitsuba's integrators that render through the lens


class LensSensor(LensFilm):
    """The `lens_sensor` sensor (parameters: the module docstring; the film, lens, response, pupil and
    wavelengths: `lens_film.LensFilm`)."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(
            props, "lens_sensor", "lines", f"the integrators {', '.join(INTEGRATORS)} or solas-mi's render loop"
        )
        self.fov_deg = self.field_deg(props)
        # a lens of polar fields (a fisheye) has no pinhole image: its units are those of the paraxial camera
        self.focal_mm = (
            pinhole_focal_mm(self.lens, self.fov_deg) if self.lens.field_type.pinhole else paraxial(self.lens).efl_mm
        )
        self.norm = 1.0 / ideal_irradiance(self.lens, self.focal_mm)
        heights, radial, tangential = image_scales(self.lens, self.half_diagonal_mm, self.lens.primary_wavelength)
        self.scale_step = float(heights[1] - heights[0]) if heights[-1] > 0 else 1.0
        self.inv_radial, self.inv_tangential = table(1.0 / radial), table(1.0 / tangential)
        self.scale_rows = len(heights)
        self.max_footprint = float(self.pitch_mm / min(radial.min(), tangential.min()))
        r = self.response
        self.checked = set()  # ids of the integrators found to render through the lens
        self.channel_table = table(r.weights)
        self.channels = len(r.channels)
        # a response of equally likely spectral lines (lines, mono) lets a render stratify by line
        lines = np.all(r.lo_nm == r.hi_nm) and np.allclose(r.probability, 1.0 / len(r.probability))
        self.discrete_lines = len(r.probability) if lines else 0

    def field_deg(self, props: mi.Properties) -> float:
        """The half field the input image spans, which the film's width spans where no `pitch_um` is given."""
        return float(props.get("fov_deg", self.lens.field_deg))

    def prepared(self, lens: Lens, props: mi.Properties) -> Lens:
        """The lens, which must be focused at infinity (SolasError otherwise)."""
        if not lens.at_infinity:
            raise SolasError(
                f"lens_sensor: lens {lens.name} has a finite object; the sensor needs a lens "
                "focused at infinity (put a near object in the scene with image_object's distance_mm)"
            )
        return lens

    def channel_weights(self, index: mi.UInt32, active=True) -> list[mi.Float]:
        """Per-channel weight response_c(λ)/p(λ) of the wavelength bin `index`."""
        return [lookup(self.channel_table, index * self.channels + c, active) for c in range(self.channels)]

    def footprint(self, film: mi.Point2f) -> mi.Vector2f:
        """Widths in field tangent (x, y) that the pixel centred at film point (x, y) mm covers on the
        object: the pitch over the chief ray's radial and tangential image scales there."""
        r = dr.sqrt(dr.squared_norm(film))
        f = r / self.scale_step
        i = dr.minimum(mi.UInt32(f), self.scale_rows - 2)
        w = dr.clip(f - mi.Float(i), 0.0, 1.0)
        inv_r = dr.lerp(lookup(self.inv_radial, i), lookup(self.inv_radial, i + 1), w)
        inv_t = dr.lerp(lookup(self.inv_tangential, i), lookup(self.inv_tangential, i + 1), w)
        c2 = dr.select(r > 0, dr.square(film.x / r), 1.0)
        return mi.Vector2f(
            self.pitch_mm * (c2 * inv_r + (1.0 - c2) * inv_t), self.pitch_mm * ((1.0 - c2) * inv_r + c2 * inv_t)
        )

    def sample_ray(self, time, sample1, sample2, sample3, active=True):
        """A camera ray for Mitsuba's integrators: `pupil_ray` with the weight 1/p(λ) of its wavelength."""
        self.check_integrator()
        ray, weight = self.pupil_ray(time, sample1, sample2, sample3, active)
        _, inv_pdf = self.sample_wavelengths(None, sample1, active)
        return ray, weight * inv_pdf

    def pupil_ray(self, time, sample1, sample2, sample3, active=True):
        """A camera ray and its pupil weight (no wavelength weight: solas-mi's loop applies the
        response's channel weights itself)."""
        lam, _ = self.sample_wavelength(sample1, active)
        film = self.film_point(sample2)
        target, weight = self.pupil.sample(film, sample3, active)
        origin = mi.Point3f(film.x, film.y, self.image_z)
        d = mi.Point3f(target.x, target.y, self.pupil.plane_z) - origin
        ray = mi.Ray3f(origin, dr.normalize(d), time, lanes(lam))
        return ray, mi.Spectrum(weight * self.norm) & active

    def check_integrator(self) -> None:
        """SolasError unless the calling render's integrator can see the scene through the lens."""
        _, integrator = calling_render()
        if integrator is None or id(integrator) in self.checked:
            return
        name = integrator_name(integrator)
        if name not in INTEGRATORS:
            raise SolasError(
                f"lens_sensor: integrator {name!r} cannot render through the lens (the sensor is "
                f"reachable only through glass); use {', '.join(INTEGRATORS)} or solas-mi's render loop"
            )
        self.checked.add(id(integrator))

    def sample_direction(self, it, sample, active=True):
        self.check_integrator()
        return super().sample_direction(it, sample, active)

    def sample_position(self, time, sample, active=True):
        """A point of the film's crop window, uniform over its area (mm²), facing the lens."""
        film = self.film_point(sample)
        ps = zeros(mi.PositionSample3f)
        ps.p = mi.Point3f(film.x, film.y, self.image_z)
        ps.n = mi.Normal3f(0.0, 0.0, -1.0)
        ps.uv, ps.time, ps.pdf, ps.delta = sample, time, mi.Float(self.pdf_area()), False
        return ps, mi.Float(1.0)

    def pdf_position(self, ps, active=True):
        return dr.select(active, self.pdf_area(), 0.0)

    def traverse(self, callback) -> None:
        super().traverse(callback)
        callback.put("fov_deg", self.fov_deg, mi.ParamFlags.ReadOnly)

    def to_string(self) -> str:
        return self.describe()


def register() -> None:
    mi.register_sensor("lens_sensor", LensSensor)  # this variant's class, bound now
