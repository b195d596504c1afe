"""`image_object` (emitter): an input image as the scene's object, at infinity (radiance as a function
of direction) or on a plane at a finite distance.

| parameter     | type   | unit    | default         | meaning                                                 |
|---------------|--------|---------|-----------------|---------------------------------------------------------|
| `filename`    | string | —       | required        | the image: PNG/JPEG (sRGB) or OpenEXR (linear)          |
| `image`       | tensor | —       | none            | from Python (`mi.load_dict`), instead of `filename`     |
| `fov_deg`     | float  | degrees | 2.0             | half the horizontal field the image's width spans       |
| `boundary`    | string | —       | "edge"          | the object outside the image: "edge", "reflect", "zero" |
| `distance_mm` | float  | mm      | 0 (at infinity) | the image on the plane z = −distance_mm instead         |
| `mapping`     | string | —       | "rectilinear"   | projection of the image at infinity (below)             |
| `scale`       | float  | —       | 1.0             | radiance multiplier                                     |
| `spectrum`    | string | —       | "srgb"          | RGB as a spectrum: "srgb" (Mitsuba's) or "bands" (below)|
| `wavelength`  | float  | nm      | 587.5618        | the wavelength of the non-spectral (mono) variants      |

`traverse` exposes `scale` (differentiable; in the JIT variants `mi.traverse` edits it without reloading
the scene; the scalar variants can read it only).

`filename` is found by Mitsuba's file resolver; `image` is a linear H×W (grey) or H×W×3 (RGB)
`mi.TensorXf`. Radiance is the texel's linear value times `scale` (relative units: the `lens_sensor`
renders radiance 1 as irradiance 1 of the ideal camera). The image's width spans ±fov_deg
horizontally, square pixels in tangent space (`solas_mi.optics.camera`); a texel is constant over its
square (nearest neighbour, the model the PSF-grid convolution uses). Outside the image "edge" repeats the border
texels, "reflect" mirrors about the border, "zero" is black. At a finite distance the plane is
centred on the axis and spans ±distance_mm·tan(fov_deg) across its width.

`spectrum` "srgb" (the colour convention of every render path, README "Colour"): a texel of linear
sRGB c emits what a Mitsuba emitter of `rgb` radiance c emits, Mitsuba's smooth spectrum of c
(`mi.srgb_model_fetch` of c/s, s = 2·max(c), evaluated by the sigmoid of `mi.srgb_model_eval`, times
s; W. Jakob, J. Hanika, "A Low-Dimensional Function Space for Efficient Spectral Upsampling",
Computer Graphics Forum 38(2), 2019) times D65 of luminance 1 (`mi.cie_d65`): Mitsuba's `hdrfilm`,
and the "srgb" response, develop it back to c. "bands": three bands
(`solas_mi.render.response.RGB_BANDS_NM`): blue below 500 nm, green to 590 nm, red above, each the
texel's channel: the model of the line responses ("lines", "mono:λ") and of the PSF-grid
convolution, which sees channel R at the red line (solas-mi's scenes write "bands" for them).
Each spectral lane takes the value at its own wavelength. A mono variant carries no wavelength:
the value is that at `wavelength`, which solas-mi's scenes set to the camera response's one
wavelength.

Rays arriving here travel away from the lens (−z): a direction d has tangents (d_x/d_z, d_y/d_z),
which is the field of light coming from there.

`mapping` (object at infinity): how the image's square pixels map to directions, for fields up to and
beyond 90°. With w = −d the light's direction of travel, θ its angle from the axis and φ its azimuth,
the image-plane point (in units where the width spans ±P(fov_deg)) is "rectilinear" tan θ (cos φ,
sin φ) (w_z > 0 only; the default), "equidistant" θ (cos φ, sin φ) (the polar fields of wide lenses,
`fields.PolarField`: field (x, y) deg sits at (x, y) in radians), "equisolid" 2 sin(θ/2) (cos φ,
sin φ) (equal area), or "equirectangular" (longitude atan2(w_x, w_z), latitude asin(w_y)), an
environment map (`plane_point`, and its inverse `plane_direction`).

Mitsuba's integrators (at infinity only, every mapping): `eval`/`eval_direction` as above;
`sample_direction` picks a texel with probability ∝ its R + G + B and a uniform point of its square on
the image plane, so `pdf_direction` = p(texel)/pitch² × dA/dω per steradian, dA/dω the mapping's
image-plane area per steradian (`plane_direction`; (1 + t_x² + t_y²)^(3/2) rectilinear) (0 outside the image: the
"edge"/"reflect" surroundings are reached by BSDF sampling only); `sample_ray` (light tracing) takes
that direction and an origin on the disk of the scene's bounding sphere facing it, as Mitsuba's
`envmap` does, wavelengths uniform over 360–830 nm (`sample_wavelengths`, `pdf_wavelengths`); light
tracing therefore emits only the image itself, as if the boundary were "zero".
An infinite emitter has no position: `sample_position` returns pdf NaN, `pdf_position` 0. Mitsuba does
not pass the scene to Python emitters, so its bounding sphere comes from `set_scene(scene)` (Mitsuba's
name; called on first need with the scene of the calling render, `plugins/scene_probe.py`).
Mitsuba hands an emitter no ray origin, so an object at a finite distance works only in solas-mi's
loop (`radiance`); in a stock render `eval` stops with a SolasError. There, put the image on a
`rectangle` with an `area` emitter whose `radiance` is a `bitmap` texture (`filter_type` "nearest";
a linear EXR), `to_world` = scale(x = −distance_mm·tan(fov_deg), y = +that × height/width), then
translate(z = −distance_mm): the mirrored x puts image column 0 at +x, where the lens images it on the
left. `bitmap` turns RGB into Mitsuba's smooth spectra, as `spectrum` "srgb" does, but Mitsuba 3.9's
`area` emitter does not multiply a bitmap by D65 (its `envmap` and `rgb` radiance do): such a
rectangle renders the image × hdrfilm's flat-spectrum white (1.206, 0.949, 0.910) (and a bitmap clips
values above 1), tests/render/test_stock_integrators.py.
"""
from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np
from solas_mi.plugins.rgb_spectrum import sigmoid, upsampled
from solas_mi.plugins.scene_probe import calling_render
from solas_mi.plugins.tables import lookup, table, zeros
from solas_mi.plugins.wavelength_sampling import mono_wavelength

from solas_mi.errors import SolasError
from solas_mi.imageio import read_image
from solas_mi.optics.camera import BOUNDARIES, MAPPINGS
from solas_mi.render.response import RGB_BANDS_NM

SPECTRUM_NM = (mi.MI_CIE_MIN, mi.MI_CIE_MAX)  # light tracing samples wavelengths uniformly here
SPECTRA = ("srgb", "bands")


def half_width(mapping: str, fov_deg: float) -> float:
    """Image-plane half width P(fov_deg) of an image spanning ±fov_deg in `mapping` (module docstring)."""
    t = math.radians(fov_deg)
    return {"rectilinear": math.tan(t), "equidistant": t, "equisolid": 2.0 * math.sin(t / 2.0),
            "equirectangular": t}[mapping]


def plane_point(mapping: str, wx, wy, wz):
    """Image-plane point (a, b) of the light's direction of travel w (unit) in `mapping`, and whether
    the mapping covers it."""
    if mapping == "rectilinear":
        z = dr.select(wz > 0, wz, 1.0)
        return wx / z, wy / z, wz > 0
    if mapping == "equirectangular":
        return dr.atan2(wx, wz), dr.asin(dr.clip(wy, -1.0, 1.0)), wz > -2.0
    s = dr.sqrt(wx * wx + wy * wy)
    theta = dr.atan2(s, wz)
    r = theta if mapping == "equidistant" else 2.0 * dr.sin(0.5 * theta)
    k = dr.select(s > 0, r / dr.select(s > 0, s, 1.0), 1.0)
    return wx * k, wy * k, theta < math.pi


def in_domain(mapping: str, a, b):
    """Whether the mapping covers image-plane point (a, b) (NumPy or Dr.Jit arrays): every point
    rectilinear; θ ≤ π equidistant; r ≤ 2 (θ ≤ π) equisolid; |longitude| ≤ π and |latitude| < π/2
    equirectangular."""
    if mapping == "rectilinear":
        return a == a
    if mapping == "equirectangular":
        return (a * a <= math.pi ** 2) & (b * b < 0.25 * math.pi ** 2)
    return a * a + b * b <= (math.pi ** 2 if mapping == "equidistant" else 4.0)


def plane_direction(mapping: str, a, b):
    """The inverse of `plane_point`: the light's direction of travel w (unit) at image-plane point
    (a, b) in `mapping`, the image-plane area per steradian there (dA/dω: (1 + a² + b²)^(3/2)
    rectilinear, θ/sin θ equidistant, 1 equisolid, 1/cos(latitude) equirectangular), and whether the
    mapping covers the point (`in_domain`)."""
    covered = in_domain(mapping, a, b)
    if mapping == "rectilinear":
        q = 1.0 + a * a + b * b
        inv = dr.rsqrt(q)
        return mi.Vector3f(a * inv, b * inv, inv), q * dr.sqrt(q), covered
    if mapping == "equirectangular":
        cos_b = dr.cos(b)
        return (mi.Vector3f(cos_b * dr.sin(a), dr.sin(b), cos_b * dr.cos(a)),
                dr.rcp(dr.maximum(cos_b, 1e-12)), covered)
    r = dr.sqrt(a * a + b * b)
    theta = r if mapping == "equidistant" else 2.0 * dr.asin(dr.minimum(0.5 * r, 1.0))
    sin_t = dr.sin(theta)
    k = dr.select(r > 0, sin_t / dr.select(r > 0, r, 1.0), 1.0)
    area = 1.0 if mapping == "equisolid" else dr.select(theta > 1e-4, theta / dr.maximum(sin_t, 1e-12),
                                                         1.0 + theta * theta / 6.0)
    return mi.Vector3f(a * k, b * k, dr.cos(theta)), mi.Float(area), covered


def _fold(i, n: int, boundary: str):
    """Integer texel index i folded into [0, n) by the boundary rule, and whether it is inside."""
    if boundary == "reflect":
        m = i - 2 * n * mi.Int32(dr.floor(mi.Float(i) / (2 * n)))
        return dr.select(m >= n, 2 * n - 1 - m, m), True
    return dr.clip(i, 0, n - 1), ((i >= 0) & (i < n)) if boundary == "zero" else True


class ImageObject(mi.Emitter):
    """The `image_object` emitter (parameters: the module docstring)."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        self.m_flags = mi.EmitterFlags.Infinite
        self.boundary = str(props.get("boundary", "edge"))
        if self.boundary not in BOUNDARIES:
            raise SolasError(f"image_object boundary {self.boundary!r} must be one of {', '.join(BOUNDARIES)}")
        self.fov_deg = float(props.get("fov_deg", 2.0))
        distance = props.get("distance_mm", 0.0)
        self.distance = float(distance) if distance else math.inf
        self.wavelength = mono_wavelength(props, "image_object")
        self.mapping = str(props.get("mapping", "rectilinear"))
        if self.mapping not in MAPPINGS:
            raise SolasError(f"image_object mapping {self.mapping!r} must be one of {', '.join(MAPPINGS)}")
        if self.mapping != "rectilinear" and not math.isinf(self.distance):
            raise SolasError(f"image_object mapping {self.mapping!r} is for an object at infinity; an image at "
                             f"distance_mm {self.distance:g} is rectilinear")
        image = props.get("image", None)  # a tensor from Python (`mi.load_dict`); else the file
        if image is None:
            image = read_image(str(mi.file_resolver().resolve(str(props.get("filename")))))
        rgb = np.asarray(image, dtype=np.float32)
        if rgb.ndim == 2:
            rgb = np.repeat(rgb[..., None], 3, axis=-1)
        if rgb.ndim != 3 or rgb.shape[-1] != 3:
            raise SolasError(f"image_object: image of shape {rgb.shape} must be H x W (grey) or H x W x 3 (RGB)")
        self.height, self.width = rgb.shape[:2]
        self.spectrum = str(props.get("spectrum", "srgb"))
        if self.spectrum not in SPECTRA:
            raise SolasError(f"image_object spectrum {self.spectrum!r} must be one of {', '.join(SPECTRA)}")
        if self.spectrum == "srgb":
            coeff, scale = upsampled(rgb)
            self.texels, self.texel_scale = table(coeff), table(scale)
        else:
            self.texels = table(rgb)
        self.scale = mi.Float(float(props.get("scale", 1.0)))
        self.tan_pitch = half_width(self.mapping, self.fov_deg) / (self.width / 2)  # image-plane units per texel
        weights = np.maximum(rgb, 0.0).sum(axis=-1).ravel()
        weights = weights if weights.sum() > 0 else np.ones_like(weights)  # a black image: uniform
        weights = np.where(self._texels_seen(), weights, 0.0)  # none drawn wholly outside the mapping's domain
        self.texel_distribution = mi.DiscreteDistribution(table(weights))
        self.bsphere = None  # (centre, radius) of the scene, from set_scene

    def _texels_seen(self) -> np.ndarray:
        """Per texel (row-major), whether a corner or the centre of its square is a direction of the
        mapping (`in_domain`); texels wholly beyond it (an equisolid image reaching past 180°,
        an equirectangular one past the poles) are never sampled."""
        col, row = np.meshgrid(np.arange(2 * self.width + 1) / 2.0, np.arange(2 * self.height + 1) / 2.0)
        a = (col - self.width / 2) * self.tan_pitch
        b = (self.height / 2 - row) * self.tan_pitch
        covered = in_domain(self.mapping, a, b)
        seen = covered[0::2, 0::2][:-1, :-1] | covered[0::2, 2::2][:-1] | covered[2::2, 0::2][:, :-1] | \
            covered[2::2, 2::2] | covered[1::2, 1::2]
        return seen.ravel()

    def set_scene(self, scene) -> None:
        """Take the bounding sphere of `scene` (light tracing starts rays on its disks)."""
        box = scene.bbox()
        self.bsphere = (mi.ScalarPoint3f(box.center()), max(float(dr.norm(box.extents())) / 2, 1e-3)) \
            if box.valid() else (mi.ScalarPoint3f(0.0), 1.0)

    def bounding_sphere(self):
        if self.bsphere is None:
            scene, _ = calling_render()
            if scene is None:
                raise SolasError("image_object: the scene's bounds are unknown; call set_scene(scene) first")
            self.set_scene(scene)
        return self.bsphere


    def radiance(self, o: mi.Point3f, d: mi.Vector3f, wavelengths, active=True, footprint=None) -> mi.Spectrum:
        """Radiance toward the lens along the ray (o, d) that left the lens; one value in every lane.
        With `footprint` (widths in field tangent, at most two texels), the mean radiance over that
        box centred on the ray: the exact area-weighted texels of a piecewise-constant image."""
        if math.isinf(self.distance):
            tx, ty, covered = plane_point(self.mapping, -d.x, -d.y, -d.z)
            active = active & covered
        else:  # the point on the plane z = −distance, as a tangent seen from the axis at z = 0
            t = (-self.distance - o.z) / d.z
            tx, ty = (o.x + t * d.x) / self.distance, (o.y + t * d.y) / self.distance
            tx, ty = -tx, -ty  # a point at +x on the plane sends light of field −x
        u, v = self._texel_uv(tx, ty)
        lam = wavelengths[0] if mi.is_spectral else self.wavelength
        if self.mapping == "rectilinear":
            active = active & (d.z < 0)
        if footprint is None:
            return mi.Spectrum(self._texel(dr.floor(u), dr.floor(v), lam, active))
        hu, hv = 0.5 * footprint.x / self.tan_pitch, 0.5 * footprint.y / self.tan_pitch
        u0, v0 = dr.floor(u - hu), dr.floor(v - hv)
        total = mi.Float(0.0)
        for j in range(3):
            wv = dr.maximum(dr.minimum(v0 + j + 1, v + hv) - dr.maximum(v0 + j, v - hv), 0.0)
            for i in range(3):
                wu = dr.maximum(dr.minimum(u0 + i + 1, u + hu) - dr.maximum(u0 + i, u - hu), 0.0)
                w = wu * wv
                total += w * self._texel(u0 + i, v0 + j, lam, active & (w > 0))
        return mi.Spectrum(total / (4.0 * hu * hv))

    def _texel(self, u: mi.Float, v: mi.Float, lam, active) -> mi.Float:
        """Radiance at wavelength `lam` (nm) of texel (column u, row v) (integral floats), folded by the
        boundary rule (`spectrum`: the module docstring)."""
        col, ok_c = _fold(mi.Int32(u), self.width, self.boundary)
        row, ok_r = _fold(mi.Int32(v), self.height, self.boundary)
        index, active = mi.UInt32(row) * self.width + mi.UInt32(col), active & ok_c & ok_r
        if self.spectrum == "bands":
            channel = dr.select(lam < RGB_BANDS_NM[0], 2, dr.select(lam < RGB_BANDS_NM[1], 1, 0))
            return lookup(self.texels, index * 3 + mi.UInt32(channel), active) * self.scale
        s = lookup(self.texel_scale, index, active)
        c0, c1, c2 = (lookup(self.texels, index * 3 + k, active) for k in range(3))
        return dr.select(s > 0, sigmoid(c0, c1, c2, lam) * s, 0.0) * mi.cie_d65(lam) * self.scale

    # ---- Mitsuba's Emitter interface (stock integrators), the object at infinity ----

    def _texel_uv(self, a, b):
        """Continuous texel coordinates (u, v) of image-plane point (a, b)."""
        return a / self.tan_pitch + self.width / 2, self.height / 2 - b / self.tan_pitch

    def _tangent(self, d: mi.Vector3f):
        """Continuous texel coordinates (u, v) of direction d (toward the object), and whether the
        mapping covers it (rectilinear: d.z < 0)."""
        a, b, covered = plane_point(self.mapping, -d.x, -d.y, -d.z)
        return (*self._texel_uv(a, b), covered)

    def _lanes(self, u, v, wavelengths, active) -> mi.Spectrum:
        """Radiance of texel coordinates (u, v), each spectral lane at its own wavelength."""
        if not mi.is_spectral:
            return mi.Spectrum(self._texel(dr.floor(u), dr.floor(v), self.wavelength, active))
        value = mi.Spectrum(0.0)
        for i in range(4):
            value[i] = self._texel(dr.floor(u), dr.floor(v), wavelengths[i], active)
        return value

    def _at_infinity(self) -> None:
        if not math.isinf(self.distance):
            raise SolasError(f"image_object at distance_mm {self.distance:g}: Mitsuba's integrators give an emitter no "
                             "ray origin; use solas-mi's render loop, or a rectangle with an area emitter and a bitmap "
                             "texture (plugins/image_object.py)")

    def eval(self, si, active=True):
        self._at_infinity()
        u, v, front = self._tangent(-si.wi)
        return self._lanes(u, v, si.wavelengths, active & front)

    def eval_direction(self, it, ds, active=True):
        self._at_infinity()
        u, v, front = self._tangent(ds.d)
        return self._lanes(u, v, it.wavelengths, active & front)

    def _sample_texel(self, sample: mi.Point2f, active):
        """(direction toward the object, texel coordinates u, v, pdf per steradian): a texel by its
        weight, a uniform point of its square on the image plane, that point's direction in the
        mapping (pdf 0 where the mapping does not cover it)."""
        index, x = self.texel_distribution.sample_reuse(sample.x, active)
        u, v = mi.Float(index % self.width) + x, mi.Float(index // self.width) + sample.y
        a, b = (u - self.width / 2) * self.tan_pitch, (self.height / 2 - v) * self.tan_pitch
        w, area, covered = plane_direction(self.mapping, a, b)
        pmf = self.texel_distribution.eval_pmf_normalized(index, active)
        return -w, u, v, dr.select(covered, pmf / (self.tan_pitch ** 2) * area, 0.0)

    def sample_direction(self, it, sample, active=True):
        self._at_infinity()
        d, u, v, pdf = self._sample_texel(sample, active)
        centre, radius = self.bounding_sphere()
        dist = 2.0 * dr.maximum(radius, dr.norm(it.p - centre))
        ds = zeros(mi.DirectionSample3f)
        ds.p, ds.n, ds.uv, ds.time = it.p + d * dist, -d, mi.Point2f(u / self.width, v / self.height), it.time
        ds.pdf, ds.delta, ds.d, ds.dist = dr.select(active, pdf, 0.0), False, d, dist
        ds.emitter = mi.EmitterPtr(self) if dr.is_jit_v(mi.Float) else self
        value = self._lanes(u, v, it.wavelengths, active)
        return ds, dr.select(active & (pdf > 0), value / pdf, 0.0)

    def pdf_direction(self, it, ds, active=True):
        self._at_infinity()
        d = dr.normalize(ds.d)
        a, b, front = plane_point(self.mapping, -d.x, -d.y, -d.z)
        u, v = self._texel_uv(a, b)
        inside = front & (u >= 0) & (u < self.width) & (v >= 0) & (v < self.height) & active
        index = mi.UInt32(dr.clip(dr.floor(v), 0, self.height - 1)) * self.width + \
            mi.UInt32(dr.clip(dr.floor(u), 0, self.width - 1))
        _, area, covered = plane_direction(self.mapping, a, b)
        pdf = self.texel_distribution.eval_pmf_normalized(index, inside) / (self.tan_pitch ** 2) * area
        return dr.select(inside & covered, pdf, 0.0)

    def sample_wavelengths(self, si, sample, active=True):
        """Wavelengths uniform over SPECTRUM_NM, weighted by the radiance at si.uv over their pdf (a mono
        variant: none, and the radiance at `wavelength`)."""
        u, v = si.uv.x * self.width, si.uv.y * self.height
        if not mi.is_spectral:
            return mi.Color0f(), self._lanes(u, v, None, active)
        lo, hi = SPECTRUM_NM
        lam = mi.Spectrum(lo + (hi - lo) * mi.sample_shifted(sample))
        return lam, self._lanes(u, v, lam, active) * (hi - lo)

    def pdf_wavelengths(self, wavelengths, active=True):
        lo, hi = SPECTRUM_NM
        return dr.select((wavelengths >= lo) & (wavelengths <= hi), 1.0 / (hi - lo), 0.0)

    def sample_ray(self, time, sample1, sample2, sample3, active=True):
        self._at_infinity()
        d, u, v, pdf = self._sample_texel(sample3, active)
        centre, radius = self.bounding_sphere()
        offset = mi.warp.square_to_uniform_disk_concentric(sample2)
        origin = centre + (mi.Frame3f(d).to_world(mi.Vector3f(offset.x, offset.y, 0.0)) + d) * radius
        si = zeros(mi.SurfaceInteraction3f)
        si.time, si.p, si.uv = time, origin, mi.Point2f(u / self.width, v / self.height)
        wavelengths, weight = self.sample_wavelengths(si, sample1, active)
        ray = mi.Ray3f(origin, -d, time, wavelengths)
        return ray, dr.select(active & (pdf > 0), weight * (dr.pi * radius * radius) / pdf, 0.0)

    def sample_position(self, time, sample, active=True):
        return zeros(mi.PositionSample3f), mi.Float(dr.nan)  # an infinite emitter has no position

    def pdf_position(self, ps, active=True):
        return mi.Float(0.0)

    def bbox(self):
        return mi.ScalarBoundingBox3f()

    def traverse(self, callback) -> None:
        callback.put("scale", self.scale, mi.ParamFlags.Differentiable)

    def to_string(self) -> str:
        where = "infinity" if math.isinf(self.distance) else f"{self.distance:g} mm"
        return (f"ImageObject[{self.width}x{self.height}, fov=+-{self.fov_deg:g} deg, {self.mapping}, at {where}, "
                f"{self.boundary}, {self.spectrum}]")


def register() -> None:
    mi.register_emitter("image_object", ImageObject)  # this variant's class, bound now
