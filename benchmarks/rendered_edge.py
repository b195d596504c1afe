"""The rendered route of `bench_sharpness`: a slanted edge rendered through the lens in Mitsuba (the lens as
geometry, `render.image`'s scene) and measured by e-SFR.

The object is an image at infinity (`image_object`) whose width spans a few degrees about the axis and
whose height reaches past the field: a step (0.2 to 0.8) through the field's point of the image's mapping
(rectilinear tan θ, or equidistant θ for a lens of polar fields), tilted `bench_sharpness.TILT_DEG` from its
columns or rows, in square texels of 1/`TEXELS_PER_PX` of a pixel (nearest neighbour: the staircase is a
ramp of one texel across the edge, in the prediction as `bench_sharpness.predicted`'s `ramp_px`). The
sensor is a film of the bench's pitch reaching past the field, of which only a `ROI_PX`² crop window
centred on the chief ray's image point is rendered (`lens_film`: a crop is exactly those pixels of the
whole film). The crop is divided by the same crop rendered from a uniform object (flat field: relative
illumination and Fresnel losses vary by several % across it, which e-SFR would read as a slope of the
edge's profile), then measured by `metrics.esfr`. Two seeds per edge: their spread is the render noise.
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import numpy as np

ROI_PX = 96  # the rendered crop, pixels across the edge
ALONG_PX = 96  # and along it
SPP = 256  # samples per pixel of each render
SEEDS = (0, 1)
TEXELS_PER_PX = 8  # object texels per pixel side at the field
STEP = (0.2, 0.8)
DELTA_DEG = 0.05  # the field step of the finite differences of the chief ray's image point


def mapping_of(lens) -> tuple[str, object]:
    """The image object's mapping for the lens, and its image-plane coordinate of a field angle (deg)."""
    if lens.field_type.pinhole:
        return "rectilinear", lambda deg: math.tan(math.radians(deg))
    return "equidistant", math.radians


def field_point(lens, field: float, wavelength: float) -> tuple[np.ndarray, float, float]:
    """The chief ray's image point (mm) at field (0, `field`) and the image's mm per unit of the mapping's
    coordinate there, radially (y) and across (x)."""
    from solas_mi.optics.pupil import chief_rays

    _, coordinate = mapping_of(lens)
    d = DELTA_DEG
    fields = np.array([[0.0, field], [0.0, field + d], [0.0, field - d], [d, field]])
    xy = chief_rays(lens, fields, np.full(4, wavelength)).image_xy
    radial = abs(xy[1, 1] - xy[2, 1]) / (coordinate(field + d) - coordinate(field - d))
    across = abs(xy[3, 0]) / coordinate(d)
    return xy[0], radial, across


def edge_object(lens, field: float, pitch_um: float, scale: tuple[float, float], normal: str):
    """(image, fov_deg, texel in pixels along the normal): the step through the field's point (module
    docstring), its texels 1/TEXELS_PER_PX of a pixel in the image's larger scale, spanning 0.75 ROI past
    the crop on every side."""
    from bench_sharpness import TILT_DEG

    _, coordinate = mapping_of(lens)
    radial, across = scale
    texel = pitch_um * 1e-3 / TEXELS_PER_PX / max(radial, across)
    half_w = 0.75 * ROI_PX * pitch_um * 1e-3 / across
    half_h = coordinate(field) + 0.75 * ROI_PX * pitch_um * 1e-3 / radial
    cols, rows = (int(math.ceil(2 * h / texel)) for h in (half_w, half_h))
    u = (np.arange(cols) + 0.5 - cols / 2) * texel
    v = (rows / 2 - np.arange(rows) - 0.5)[:, None] * texel - coordinate(field)  # row 0 at +y
    t = math.radians(TILT_DEG)
    distance = u * math.cos(t) + v * math.sin(t) if normal == "x" else v * math.cos(t) - u * math.sin(t)
    image = np.where(distance > 0, STEP[1], STEP[0]).astype(np.float32)
    half = cols * texel / 2
    fov = math.degrees(half) if not lens.field_type.pinhole else math.degrees(math.atan(half))
    return image, fov, texel * (radial if normal == "y" else across) / (pitch_um * 1e-3)


def render_crop(
    lens, image: np.ndarray, spec, crop: tuple[int, int, int, int], seeds
) -> tuple[list[np.ndarray], float]:
    """The crop window (column and row of its corner, columns, rows) of the lens's render of `image`, once
    per seed (one scene, loaded once), and the seconds it took."""
    from solas_mi.imageio import image_channels, write_exr
    from solas_mi.render.image import image_sensor
    from solas_mi.render.loop import render
    from solas_mi.render.mitsuba import load_scene
    from solas_mi.render.scene import write_scene

    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="solas-sharpness-") as tmp:
        path = str(Path(tmp) / "object.exr")
        write_exr(path, image_channels(image))
        xml = write_scene(lens, tmp, path, image_sensor(lens, spec), spec)
        window = "".join(
            f'\n            <integer name="crop_{k}" value="{v}"/>'
            for k, v in zip(("offset_x", "offset_y", "width", "height"), crop)
        )
        film = '<rfilter type="box"/>'
        xml.write_text(xml.read_text().replace(film, film + window))
        scene = load_scene(xml)
        images = [render(scene, spec.spp, seed=seed).image[:, :, 0].astype(np.float64) for seed in seeds]
    return images, time.perf_counter() - start


def along_fields(
    lens, field: float, pitch_um: float, scale: tuple[float, float], normal: str, pixels: int
) -> np.ndarray:
    """The fields (deg) of the points of an edge through (0, `field`) along its `pixels` pixels, every 4th:
    radial for an edge across x (sagittal), across the field for one across y (tangential)."""
    _, coordinate = mapping_of(lens)
    inverse = math.degrees if not lens.field_type.pinhole else lambda c: math.degrees(math.atan(c))
    offsets = np.arange(-(pixels // 2), pixels // 2 + 1, 4) * pitch_um * 1e-3
    if normal == "x":
        return np.array([inverse(coordinate(field) + o / scale[0]) for o in offsets])
    return np.array([inverse(math.hypot(coordinate(field), o / scale[1])) for o in offsets])


def geometric_along(
    lens, fields: np.ndarray, wavelength: float, pitch_um: float, normal_deg: float, texel_px: float
) -> float:
    """MTF50 (cy/px) of the geometric MTF (the ray spot, 256² rays on the entrance grid: what the render
    traces) along the direction `normal_deg` from x, averaged over the fields (0, f) of `fields`, × the
    pixel's and the texel ramp's."""
    from bench_sharpness import pixel_mtf

    from solas_mi.analysis.inputs import cutoff_cy_mm
    from solas_mi.analysis.otf import spot_otf
    from solas_mi.metrics.mtf import mtf50
    from solas_mi.optics.pupil import chief_rays
    from solas_mi.psf.geometric import entrance_grid_hits

    points, wl = np.stack([np.zeros(len(fields)), fields], axis=1), np.full(len(fields), wavelength)
    freq = np.linspace(0.0, cutoff_cy_mm(lens, wavelength), 4001)
    t = math.radians(normal_deg)
    lens_mtf = np.mean(
        [
            np.abs(spot_otf((x * math.cos(t) + y * math.sin(t)) * 1e-3, power, freq))
            for x, y, power in entrance_grid_hits(lens, points, wl, 256, chief_rays(lens, points, wl))
        ],
        axis=0,
    )
    f_px = freq * pitch_um * 1e-3
    return mtf50(lens_mtf * pixel_mtf(f_px, texel_px), f_px)


def windows(point: np.ndarray, pitch_um: float, side: int) -> dict[str, tuple[int, int, int, int]]:
    """The crop windows (column, row of the corner, columns, rows) of the flat field (ROI_PX²) and of each
    edge (ROI_PX across it, ALONG_PX along it), centred on the image `point` (mm) of a `side`² film."""
    x0 = int(round(side / 2 + point[0] * 1e3 / pitch_um - ROI_PX / 2))
    y0 = int(round(side / 2 - point[1] * 1e3 / pitch_um - ROI_PX / 2))
    inset = (ROI_PX - ALONG_PX) // 2
    return {
        "flat": (x0, y0, ROI_PX, ROI_PX),
        "x": (x0, y0 + inset, ROI_PX, ALONG_PX),
        "y": (x0 + inset, y0, ALONG_PX, ROI_PX),
    }


def measure_rendered(lens, field: float, wavelength: float, pitch_um: float) -> list[dict]:
    """Both directions of one lens by the rendered route (module docstring); beside the prediction at the
    field, the MTF50 of the lens's MTF averaged over the fields along the edge in the crop."""
    from bench_sharpness import predicted

    from solas_mi.metrics.esfr import esfr
    from solas_mi.render.spec import RenderSpec

    point, *scale = field_point(lens, field, wavelength)
    side = int(2 * (np.abs(point).max() * 1e3 / pitch_um + ROI_PX)) // 2 * 2
    crops = windows(point, pitch_um, side)
    mapping, _ = mapping_of(lens)
    rows, seconds, flat = [], 0.0, None
    for direction, normal in ((0, "y"), (1, "x")):
        image, fov, texel_px = edge_object(lens, field, pitch_um, tuple(scale), normal)
        spec = RenderSpec(
            sensor=(side, side),
            pitch_um=pitch_um,
            fov_deg=fov,
            mapping=mapping,
            response=f"mono:{wavelength!r}",
            spp=SPP,
        )
        if flat is None:
            (flat,), seconds = render_crop(lens, np.ones((2, 2), np.float32), spec, crops["flat"], SEEDS[:1])
        edges, took = render_crop(lens, image, spec, crops[normal], SEEDS)
        seconds += took
        x, y, w, h = crops[normal]
        found = [
            esfr(
                e
                / flat[y - crops["flat"][1] : y - crops["flat"][1] + h, x - crops["flat"][0] : x - crops["flat"][0] + w]
            )
            for e in edges
        ]
        values = [r.mtf50 if r.valid else math.nan for r in found]
        tilt = found[0].angle_deg or 0.0  # the measured tilt from its axis; its sign the drawn one's (+)
        normal_deg = (90.0 if normal == "y" else 0.0) + tilt
        fields = along_fields(lens, field, pitch_um, tuple(scale), normal, ALONG_PX)
        rows.append(
            {
                "lens": lens.name,
                "direction": ("tangential", "sagittal")[direction],
                "texel_px": texel_px,
                "expected": predicted(lens, field, wavelength, pitch_um, direction, texel_px)[1],
                "averaged": predicted(lens, tuple(fields), wavelength, pitch_um, direction, texel_px)[1],
                "geometric": geometric_along(lens, fields, wavelength, pitch_um, normal_deg, texel_px),
                "tilt": tilt,
                "fields": (fields.min(), fields.max()),
                "esfr": float(np.mean(values)),
                "spread": abs(values[0] - values[-1]),
                "reason": "; ".join(r.reason for r in found if not r.valid),
            }
        )
    for r in rows:
        r["seconds"] = seconds / len(rows)
    return rows
