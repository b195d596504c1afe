"""`image_object` (emitter): an input image as the scene's object, at infinity (radiance as a function
of direction) or on a plane at a finite distance.

| parameter     | type   | unit    | default         | meaning                                                 |
|---------------|--------|---------|-----------------|---------------------------------------------------------|
| `filename`    | string | —       | required        | the image: PNG/JPEG (sRGB) or OpenEXR (linear)          |
| `image`       | tensor | —       | none            | from Python (`mi.load_dict`), instead of `filename`     |
| `fov_deg`     | float  | degrees | 2.0             | half the horizontal field the image's width spans       |
| `boundary`    | string | —       | "edge"          | the object outside the image: "edge", "reflect", "zero" |
| `distance_mm` | float  | mm      | 0 (at infinity) | the image on the plane z = −distance_mm instead         |
| `scale`       | float  | —       | 1.0             | radiance multiplier                                     |

`traverse` exposes nothing: no parameter is differentiable or editable through `mi.traverse`.

`filename` is found by Mitsuba's file resolver; `image` is a linear H×W (grey) or H×W×3 (RGB)
`mi.TensorXf`. Radiance is the texel's linear value times `scale` (relative units: the `lens_sensor`
renders radiance 1 as irradiance 1 of the ideal camera). The image's width spans ±fov_deg
horizontally, square pixels in tangent space (`solas_mi.optics.camera`); a texel is constant over its
square (nearest neighbour, the model the PSF-grid convolution uses). Outside the image "edge" repeats the border
texels, "reflect" mirrors about the border, "zero" is black. At a finite distance the plane is
centred on the axis and spans ±distance_mm·tan(fov_deg) across its width. RGB becomes a spectrum of
three bands (`solas_mi.render.response.RGB_BANDS_NM`): blue below 500 nm, green to 590 nm, red above.

Rays arriving here travel away from the lens (−z): a direction d has tangents (d_x/d_z, d_y/d_z),
which is the field of light coming from there.
"""
from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from solas_mi.errors import SolasError
from solas_mi.imageio import read_image
from solas_mi.optics.camera import BOUNDARIES
from solas_mi.plugins.tables import lookup, table
from solas_mi.render.response import RGB_BANDS_NM


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
        image = props.get("image", None)  # a tensor from Python (`mi.load_dict`); else the file
        if image is None:
            image = read_image(str(mi.file_resolver().resolve(str(props.get("filename")))))
        rgb = np.asarray(image, dtype=np.float32)
        if rgb.ndim == 2:
            rgb = np.repeat(rgb[..., None], 3, axis=-1)
        if rgb.ndim != 3 or rgb.shape[-1] != 3:
            raise SolasError(f"image_object: image of shape {rgb.shape} must be H x W (grey) or H x W x 3 (RGB)")
        self.height, self.width = rgb.shape[:2]
        self.texels = table(rgb * float(props.get("scale", 1.0)))
        self.tan_pitch = math.tan(math.radians(self.fov_deg)) / (self.width / 2)

    def radiance(self, o: mi.Point3f, d: mi.Vector3f, wavelengths, active=True, footprint=None) -> mi.Spectrum:
        """Radiance toward the lens along the ray (o, d) that left the lens; one value in every lane.
        With `footprint` (widths in field tangent, at most two texels), the mean radiance over that
        box centred on the ray: the exact area-weighted texels of a piecewise-constant image."""
        if math.isinf(self.distance):
            tx, ty = d.x / d.z, d.y / d.z
        else:  # the point on the plane z = −distance, as a tangent seen from the axis at z = 0
            t = (-self.distance - o.z) / d.z
            tx, ty = (o.x + t * d.x) / self.distance, (o.y + t * d.y) / self.distance
            tx, ty = -tx, -ty  # a point at +x on the plane sends light of field −x
        u = tx / self.tan_pitch + self.width / 2  # continuous texel coordinates
        v = self.height / 2 - ty / self.tan_pitch
        lam = wavelengths[0] if mi.is_spectral else 550.0
        channel = mi.UInt32(dr.select(lam < RGB_BANDS_NM[0], 2, dr.select(lam < RGB_BANDS_NM[1], 1, 0)))
        active = active & (d.z < 0)
        if footprint is None:
            return mi.Spectrum(self._texel(dr.floor(u), dr.floor(v), channel, active))
        hu, hv = 0.5 * footprint.x / self.tan_pitch, 0.5 * footprint.y / self.tan_pitch
        u0, v0 = dr.floor(u - hu), dr.floor(v - hv)
        total = mi.Float(0.0)
        for j in range(3):
            wv = dr.maximum(dr.minimum(v0 + j + 1, v + hv) - dr.maximum(v0 + j, v - hv), 0.0)
            for i in range(3):
                wu = dr.maximum(dr.minimum(u0 + i + 1, u + hu) - dr.maximum(u0 + i, u - hu), 0.0)
                w = wu * wv
                total += w * self._texel(u0 + i, v0 + j, channel, active & (w > 0))
        return mi.Spectrum(total / (4.0 * hu * hv))

    def _texel(self, u: mi.Float, v: mi.Float, channel: mi.UInt32, active) -> mi.Float:
        """Value of texel (column u, row v) (integral floats), folded by the boundary rule."""
        col, ok_c = _fold(mi.Int32(u), self.width, self.boundary)
        row, ok_r = _fold(mi.Int32(v), self.height, self.boundary)
        index = (mi.UInt32(row) * self.width + mi.UInt32(col)) * 3 + channel
        return lookup(self.texels, index, active & ok_c & ok_r)

    def eval(self, si, active=True):
        return self.radiance(si.p, -si.wi, si.wavelengths, active)

    def traverse(self, callback) -> None:
        pass

    def to_string(self) -> str:
        where = "infinity" if math.isinf(self.distance) else f"{self.distance:g} mm"
        return f"ImageObject[{self.width}x{self.height}, fov=+-{self.fov_deg:g} deg, at {where}, {self.boundary}]"


def register() -> None:
    mi.register_emitter("image_object", lambda props: ImageObject(props))
