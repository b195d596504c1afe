"""The slanted-edge benchmark's geometry and prediction (`benchmarks/rendered_edge.py`,
`benchmarks/bench_sharpness.py`): the rendered edge's image is tilted as the degraded one, and the MTF50
along the edge's normal is that of the PSF projected on it, and the crop built from its rows' geometric spots
reads by e-SFR the field's MTF where its rows share one field."""

import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import bench_sharpness
import rendered_edge


@pytest.mark.parametrize("normal", ["x", "y"])
def test_the_rendered_edge_is_tilted_as_the_degraded_one_in_the_image(normal):
    """On the fisheye at 63° the across scale is 1.18 × the radial: an object tilted 5° came out at 5.98°.
    Two points of the object's edge line, traced by chief rays, give the image's tilt."""
    from solas_mi import Lens
    from solas_mi.optics.pupil import chief_rays

    lens = Lens.load("nikkor-fisheye")
    wl, field = lens.primary_wavelength, 63.0
    _, scale_radial, scale_across = rendered_edge.field_point(lens, field, wl)
    assert scale_across / scale_radial > 1.1  # the case that matters: the scales differ
    t = rendered_edge.object_tilt((scale_radial, scale_across), normal)
    s = np.array([-0.01, 0.01])  # radians of the equidistant mapping, along the edge
    u, v = (-s * math.tan(t), math.radians(field) + s) if normal == "x" else (s, math.radians(field) + s * math.tan(t))
    xy = chief_rays(lens, np.degrees(np.stack([u, v], axis=1)), np.full(2, wl)).image_xy
    dx, dy = np.abs(xy[1] - xy[0])
    tilt = math.degrees(math.atan2(dx, dy) if normal == "x" else math.atan2(dy, dx))
    assert tilt == pytest.approx(bench_sharpness.TILT_DEG, abs=0.02)


@pytest.mark.parametrize("direction", [0, 1])
def test_the_mtf50_along_the_edge_normal_is_the_projected_psfs(direction):
    """A Gaussian PSF of σx ≠ σy: along a normal at angle a its MTF is exp(−2π²ν²(σx²cos²a + σy²sin²a)),
    times the pixel's and ramp's, whose half is found by bisection here."""
    pitch_um, sx, sy = 10.0, 4.0, 12.0  # µm
    n = 256
    c = (np.arange(n) - n // 2) * pitch_um / bench_sharpness.OVERSAMPLE
    x, y = np.meshgrid(c, -c)
    psf = SimpleNamespace(data=np.exp(-0.5 * ((x / sx) ** 2 + (y / sy) ** 2)))
    a = math.radians(bench_sharpness.TILT_DEG + (90.0 if direction == 0 else 0.0))
    variance = (sx * math.cos(a)) ** 2 + (sy * math.sin(a)) ** 2  # µm²

    def mtf(f_px: float) -> float:
        nu = f_px / pitch_um  # cycles/µm
        lens = math.exp(-2.0 * math.pi**2 * nu**2 * variance)
        return lens * float(bench_sharpness.pixel_mtf(np.array([f_px]), 1.0 / bench_sharpness.OVERSAMPLE)[0]) - 0.5

    lo, hi = 0.0, 0.5
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if mtf(mid) > 0 else (lo, mid)
    assert bench_sharpness.normal_mtf50(psf, pitch_um, direction) == pytest.approx(lo, rel=2e-3)


def test_the_geometric_crop_at_one_field_reads_that_fields_mtf_and_its_rows_fields_lower():
    """e-SFR of the crop whose rows all have the field's geometric spot is that spot's MTF50 along the
    edge's normal (× pixel × ramp, the independent route: the spot's OTF); the fisheye's 32 sagittal rows at
    their own fields (58°-68°, blur changing steadily along the edge) read 6 % lower, where their mean OTF
    (an earlier prediction) is only 1 % lower."""
    from solas_mi import Lens
    from solas_mi.analysis.otf import spot_otf
    from solas_mi.metrics.mtf import mtf50
    from solas_mi.optics.pupil import chief_rays
    from solas_mi.psf.geometric import entrance_grid_hits

    lens = Lens.load("nikkor-fisheye")
    wl, field, pitch = lens.primary_wavelength, 63.0, 46.95
    point, *scale = rendered_edge.field_point(lens, field, wl)
    side = int(2 * (np.abs(point).max() * 1e3 / pitch + rendered_edge.ROI_PX)) // 2 * 2
    _, _, texel_px = rendered_edge.edge_object(lens, field, pitch, tuple(scale), "x")
    centres = rendered_edge.crop_centres(rendered_edge.windows(point, pitch, side)["x"], side, pitch)
    rows, one_field, fields = rendered_edge.geometric_crop(lens, field, wl, pitch, tuple(scale), "x", centres, texel_px)
    f_px = np.linspace(0.0, 1.0, 501)
    normal = math.radians(bench_sharpness.TILT_DEG)
    at = np.array([[0.0, field]])
    (x, y, p), *_ = entrance_grid_hits(
        lens, at, np.full(1, wl), rendered_edge.RAYS, chief_rays(lens, at, np.full(1, wl))
    )
    d = (x * math.cos(normal) + y * math.sin(normal)) * 1e-3
    otf = np.abs(spot_otf(d, p, f_px / (pitch * 1e-3))) * bench_sharpness.pixel_mtf(f_px, texel_px)
    assert one_field == pytest.approx(mtf50(otf, f_px), rel=0.01)
    assert fields.min() < field - 4 and fields.max() > field + 4
    assert rows < 0.97 * one_field


def test_a_spot_displaced_along_the_edge_brings_its_fields_blur_to_the_rows_it_lands_on():
    """Spots whose sagittal blur grows along the edge and which all land D pixels further along it: a row
    gets its light, and so its blur, from the edge's points D pixels back. The crop then reads by e-SFR as
    the crop of undisplaced spots with the blur and place of the points D back (the former model kept each
    row's own blur and read the displaced crop as the undisplaced one, 0.2609 cy/px both, where it reads 0.2323)."""
    from solas_mi.metrics.esfr import esfr

    pitch, d_px = 10.0, 6  # µm; the displacement, pixels along the edge (+y)
    centres = rendered_edge.crop_centres((0, 0, rendered_edge.ROI_PX, rendered_edge.ALONG_PX), 96, pitch)
    lines = rendered_edge.source_lines(centres[1], pitch)
    slope = -math.tan(math.radians(bench_sharpness.TILT_DEG))  # the edge, 5° from the columns
    z = np.linspace(-3.0, 3.0, 241)  # a Gaussian spot across the edge, in its σ
    span = np.ptp(centres[1])  # mm

    def spots(shift_px: float, blur_from_px: float):
        """The spots (µm), their σ from 1.5 to 1 pixel over the crop's rows (+y sharper), those of the edge's
        points `blur_from_px` back, landing `shift_px` along the edge."""
        sigma = pitch * (1.25 - 0.5 * (lines - blur_from_px * pitch * 1e-3) / span)
        return [(s * z, np.full(z.size, shift_px * pitch), np.exp(-0.5 * z**2)) for s in sigma]

    def read(shift_px: float, from_px: float) -> float:
        """e-SFR MTF50 of the crop whose edge's points have the spots and place of those `from_px` back."""
        across = slope * (lines - from_px * pitch * 1e-3)
        image = rendered_edge.crop_image(spots(shift_px, from_px), (lines, across), centres, "x", pitch, 0.125)
        return esfr(image).mtf50

    displaced, as_from_behind, own = read(d_px, 0.0), read(0.0, d_px), read(0.0, 0.0)
    assert displaced == pytest.approx(as_from_behind, rel=1e-6)
    assert abs(displaced / own - 1.0) > 0.02  # the case that matters: the rows' own blur reads otherwise
