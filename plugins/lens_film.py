"""The core of the sensors that look through a lens (`lens_sensor`, `lens_camera`): a film of square
pixels on the lens's image plane, the lens and the camera response it sees through, and the rays'
film points, pupil points and wavelengths. pbrt-v4's RealisticCamera (M. Pharr, W. Jakob,
G. Humphreys, "Physically Based Rendering: From Theory to Implementation", 4th ed., MIT Press, 2023)
is the model: what both sensors derive from their parameters is computed once, here, in the
constructor; each sensor adds only its own (`lens_sensor`: the ideal camera's units, the footprint
of a pixel, the integrator check; `lens_camera`: focus, world unit, Fresnel, the sequential trace).

Parameters read here, for both sensors (their module docstrings list them with the rest):

| parameter  | type    | unit   | default           | meaning                                             |
|------------|---------|--------|-------------------|-----------------------------------------------------|
| `lens`     | string  | —      | "solas-doublet"   | shipped lens name or lens-file path (`scene_files`) |
| `pitch_um` | float   | µm     | the film spans    | pixel pitch; default: the film's width spans the    |
|            |         |        | the field         | lens's field (logged; `to_string` says so)          |
| `response` | string  | —      | the sensor's      | camera response (`solas_mi.render.response.parse`)  |
| (film)     | film    | pixels | hdrfilm 768×576   | width × height: the film's columns × rows; its crop |
|            |         |        |                   | window (`crop_offset_x`, …): the pixels rendered    |

`traverse` exposes `pitch_um` read-only (the pupil bounds are built from it).

Film geometry, in the lens file's frame (mm; +z toward the image, +y up): the film is centred on the
axis at the image plane z = `lens.image_z`, row 0 at +y, column 0 at −x. Mitsuba's integrators (and
solas-mi's loop) pass a film sample in [0, 1]² over the crop window; `film_point` maps it onto the
image plane, so a cropped render is exactly those pixels of the whole one (`width` × `height`, the
rendered image, is the crop window's; `film_size` the whole film's). The pupil bounds cover the whole
film (its half diagonal), cropped or not.

The base class subclasses the current variant's `mi.Sensor`: `plugins.register` reloads this module
before the sensors' own.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
from solas_mi.plugins.pupil_sampling import PupilSampler
from solas_mi.plugins.scene_files import load_lens, load_response
from solas_mi.plugins.scene_probe import calling_render, integrator_name
from solas_mi.plugins.wavelength_sampling import WavelengthSampler, lanes

from solas_mi.errors import SolasError
from solas_mi.optics.camera import film_pitch_um
from solas_mi.optics.lens import Lens


def positive(props: mi.Properties, name: str, default: float, unit: str, plugin: str, infinite: bool = False) -> float:
    """A positive, finite (or, if `infinite`, also inf) float property; else a SolasError
    "<plugin>: <name> <value> must be a positive number (<unit>)"."""
    value = props.get(name, default)
    try:
        value = float(value)
    except (TypeError, ValueError):
        value = math.nan
    if not ((math.isfinite(value) or (infinite and value == math.inf)) and value > 0):
        raise SolasError(f"{plugin}: {name} {props.get(name)!r} must be a positive number ({unit})")
    return value


class LensFilm(mi.Sensor):
    """A film behind a lens (parameters and geometry: the module docstring). A sensor subclasses it
    with its plugin name (for messages), its default response, what to use instead of light tracing,
    and `prepared` for what it checks or changes in the lens before the pupil is built."""

    def __init__(self, props: mi.Properties, plugin: str, response: str, instead: str) -> None:
        super().__init__(props)
        self.plugin, self.instead = plugin, instead
        self.lens = self.prepared(load_lens(props), props)
        self.response = load_response(props, self.lens, response)
        film = self.film()
        self.film_size = tuple(int(v) for v in film.size())  # columns, rows of the whole film
        self.pitch_um = self.film_pitch(props)
        self.pitch_mm = self.pitch_um * 1e-3
        self.crop_offset = tuple(int(v) for v in film.crop_offset())
        self.crop_size = tuple(int(v) for v in film.crop_size())
        self.width, self.height = self.crop_size  # the rendered image's columns and rows
        self.film_half_mm = tuple(0.5 * self.pitch_mm * n for n in self.film_size)  # half width, half height
        self.half_diagonal_mm = math.hypot(*self.film_half_mm)  # the film's largest radius
        self.image_z = self.lens.image_z
        r = self.response
        self.pupil = PupilSampler(
            self.lens,
            self.half_diagonal_mm,
            sorted({float(r.lo_nm.min()), float(r.hi_nm.max()), *self.lens.wavelengths_nm}),
        )
        self.wavelengths = WavelengthSampler(r)

    def prepared(self, lens: Lens, props: mi.Properties) -> Lens:
        """The lens the sensor looks through, from the one its `lens` names (here: unchanged)."""
        return lens

    def field_deg(self, props: mi.Properties) -> float:
        """The half field (degrees) the film's width spans where no `pitch_um` is given: the lens's."""
        return self.lens.field_deg

    def film_pitch(self, props: mi.Properties) -> float:
        """`pitch_um`, or where none is given the pitch whose film width spans `field_deg` (as Mitsuba's
        cameras take the film's size and a field; `optics.camera.film_pitch_um`, render-image's default),
        said in `pitch_note` (`to_string`) and Mitsuba's log; SolasError where the lens sets no field."""
        if "pitch_um" in props:
            self.pitch_note = "given"
            return positive(props, "pitch_um", 1.0, "µm", self.plugin)
        field = self.field_deg(props)
        try:
            pitch = film_pitch_um(self.lens, self.film_size[0], field)
        except SolasError as exc:
            raise SolasError(
                f"{self.plugin}: no pitch_um given, and lens {self.lens.name} sets none ({exc}); give pitch_um (µm)"
            ) from None
        span = (
            f"±{field:g} deg field"
            if self.lens.field_type.pinhole
            else f"image diameter {self.lens.image_diameter:g} mm"
        )
        self.pitch_note = f"derived: the film's {self.film_size[0]} px width spans lens {self.lens.name}'s {span}"
        mi.Log(mi.LogLevel.Info, f"{self.plugin}: pitch_um {pitch:.6g} um, {self.pitch_note}")
        return pitch

    def film_point(self, sample2: mi.Point2f) -> mi.Point2f:
        """Image-plane point (x, y) mm of a film sample in [0, 1]² over the crop window (row 0 at +y)."""
        col = dr.fma(sample2.x, self.crop_size[0], self.crop_offset[0])
        row = dr.fma(sample2.y, self.crop_size[1], self.crop_offset[1])
        return mi.Point2f(
            (col - 0.5 * self.film_size[0]) * self.pitch_mm, (0.5 * self.film_size[1] - row) * self.pitch_mm
        )

    def pdf_area(self) -> float:
        """Density (mm⁻²) of `film_point` of a uniform sample: one over the crop window's area."""
        return 1.0 / (self.crop_size[0] * self.crop_size[1] * self.pitch_mm**2)

    def sample_wavelength(self, sample1: mi.Float, active=True) -> tuple[mi.Float, mi.UInt32]:
        """Wavelength (nm) of a path, from the response, and the bin it came from."""
        return self.wavelengths.sample(sample1, active)

    def sample_wavelengths(self, si, sample, active=True):
        """One wavelength (nm) from the response in all four lanes (none in a mono variant), and its
        weight 1/p(λ)."""
        lam, index = self.sample_wavelength(sample, active)
        return lanes(lam), mi.Spectrum(self.wavelengths.weight(index, active))

    def sample_ray_differential(self, time, sample1, sample2, sample3, active=True):
        ray, weight = self.sample_ray(time, sample1, sample2, sample3, active)
        return mi.RayDifferential3f(ray), weight

    def sample_direction(self, it, sample, active=True):
        """Light tracing's connection to the camera: refused, naming the calling render's integrator."""
        _, integrator = calling_render()
        name = "light tracing" if integrator is None else f"integrator {integrator_name(integrator)!r}"
        raise SolasError(
            f"{self.plugin}: {name} traces paths from the lights and must connect them to the camera "
            f"through the lens's glass, which no ray can do (the film has no direct view of the "
            f"scene); use {self.instead}"
        )

    def pdf_direction(self, it, ds, active=True):
        return self.sample_direction(it, None, active)

    def eval_direction(self, it, ds, active=True):
        return self.sample_direction(it, None, active)

    def eval(self, si, active=True):
        return mi.Spectrum(0.0)  # the film emits nothing and cannot be hit

    def bbox(self):
        """The film, in the lens's frame (mm)."""
        x, y = self.film_half_mm
        return mi.ScalarBoundingBox3f([-x, -y, self.image_z], [x, y, self.image_z])

    def traverse(self, callback) -> None:
        super().traverse(callback)
        callback.put("pitch_um", self.pitch_um, mi.ParamFlags.ReadOnly)

    def describe(self, *extra: str) -> str:
        """`to_string` of a sensor: its class, lens, film, response, then `extra`."""
        w, h = self.film_size
        parts = (
            self.lens.name,
            f"{w}x{h} px of {self.pitch_um:g} um ({self.pitch_note})",
            f"response {self.response.name}",
            *extra,
        )
        return f"{type(self).__name__}[{', '.join(parts)}]"
