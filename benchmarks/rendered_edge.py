"""The rendered route of `bench_sharpness`: a slanted edge rendered through the lens in Mitsuba (the lens as
geometry, `render.image`'s scene) and measured by e-SFR.

The object is an image at infinity (`image_object`) whose width spans a few degrees about the axis and
whose height reaches past the field: a step (0.2 to 0.8) through the field's point of the image's mapping
(rectilinear tan θ, or equidistant θ for a lens of polar fields), tilted from its columns or rows so that
its image is tilted `bench_sharpness.TILT_DEG` (`object_tilt`: the lens's radial and across scales differ),
in square texels of 1/`TEXELS_PER_PX` of a pixel (nearest neighbour: the staircase is a ramp of one texel
across the edge, in the prediction as `bench_sharpness.predicted`'s `ramp_px`). The sensor is a film of the
bench's pitch reaching past the field, of which only a crop window centred on the chief ray's image point
is rendered, `ROI_PX` across the edge and `ALONG_PX` along it (`lens_film`: a crop is exactly those pixels
of the whole film), the lens's caps meshed in RINGS rings. The crop is divided by the same crop rendered from
a uniform object (flat field: relative illumination and Fresnel losses vary by several % across it, which
e-SFR would read as a slope of the edge's profile), then measured by `metrics.esfr`. Two seeds per edge: their spread is the render noise.

e-SFR measures the MTF along the edge's normal, averaged over the rows it crosses. The prediction it is
held to is the lens's diffraction MTF along that normal at the field (`bench_sharpness.normal_mtf50`) ×
the pixel's × the texel ramp's. Beside it, the crop built from the geometric spots (what the render
traces) of the edge's points along it (`edge_rows`: on a fisheye a long crop spans tens of degrees of field,
unevenly) as the image of the bright half-plane (`crop_image`: each point's light lands in the rows its
spot sends it to, a spot several pixels long along the edge bringing the blur of the field it comes from)
measured by the same e-SFR (`geometric_crop`), and that prediction × the ratio of that crop's e-SFR to the
one field's: a 32-row crop at 63° on the fisheye spans 58°-68°, whose sagittal MTF50 falls steadily from
0.38 to 0.23 cy/px, and e-SFR reads it 6.1 % below the field's where the rows' mean OTF is 1 % below:
e-SFR bins the rows' pixels by their phase to the edge, and as the blur changes steadily along the edge each
bin holds rows of a different blur (5.3 %), and the spots, 3× longer along the edge than across, bring each
row light from the blurrier fields outward (0.8 %).
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import numpy as np

ROI_PX = 96  # the rendered crop, pixels across the edge
ALONG_PX = 32  # and along it: the rows e-SFR averages over, few, so that their fields stay near the field
SPP = 512  # samples per pixel of each render
# rings of each cap mesh: the automatic count (`render.mesh.mesh_rings`, from the meshes' blur on the axis: 32 on
# the fisheye) read the fisheye's sagittal edge at 63° 2.4 % below its 128-ring render, the meshes' blur there
RINGS = 128
RAYS = 128  # the geometric prediction's entrance grid, rays a side
SEEDS = (0, 1)
TEXELS_PER_PX = 8  # object texels per pixel side at the field
STEP = (0.2, 0.8)
MARGIN_PX = 16  # pixels along and across the crop whence the crop prediction's spots still land in it
SUBPIXELS = 8  # the crop prediction's edge points a pixel along the edge (its spots: RAYS² rays each)
ACROSS_STEPS = 64  # and its grid's steps a pixel across it
DELTA_DEG = 0.05  # the field step of the finite differences of the chief ray's image point


def mapping_of(lens):
    """The image object's mapping for the lens, its image-plane coordinate of a field angle (deg), and that
    coordinate's field angle (deg): rectilinear tan θ for a lens of angle fields, equidistant θ (radians) for
    one of polar fields (`optics.fields`: field (x, y) sits at (x, y) in either coordinate)."""
    if lens.field_type.pinhole:
        return "rectilinear", lambda deg: math.tan(math.radians(deg)), lambda c: np.degrees(np.arctan(c))
    return "equidistant", math.radians, np.degrees


def object_tilt(scale: tuple[float, float], normal: str) -> float:
    """The tilt (rad) of the object's edge from its columns (`normal` "x") or rows ("y") that the image's
    radial and across `scale` turn into TILT_DEG in the image (the degraded edge's): a fisheye's across
    scale is 1.2 × its radial one at 63°, which would turn 5° into 6° and mix 20 % more of its tangential blur
    into the sagittal edge's MTF."""
    from bench_sharpness import TILT_DEG

    radial, across = scale
    ratio = radial / across if normal == "x" else across / radial
    return math.atan(math.tan(math.radians(TILT_DEG)) * ratio)


def field_point(lens, field: float, wavelength: float) -> tuple[np.ndarray, float, float]:
    """The chief ray's image point (mm) at field (0, `field`) and the image's mm per unit of the mapping's
    coordinate there, radially (y) and across (x)."""
    from solas_mi.optics.pupil import chief_rays

    coordinate = mapping_of(lens)[1]
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
    coordinate = mapping_of(lens)[1]
    radial, across = scale
    texel = pitch_um * 1e-3 / TEXELS_PER_PX / max(radial, across)
    half_w = 0.75 * ROI_PX * pitch_um * 1e-3 / across
    half_h = coordinate(field) + 0.75 * ROI_PX * pitch_um * 1e-3 / radial
    cols, rows = (int(math.ceil(2 * h / texel)) for h in (half_w, half_h))
    u = (np.arange(cols) + 0.5 - cols / 2) * texel
    v = (rows / 2 - np.arange(rows) - 0.5)[:, None] * texel - coordinate(field)  # row 0 at +y
    t = object_tilt(scale, normal)
    distance = u * math.cos(t) + v * math.sin(t) if normal == "x" else v * math.cos(t) - u * math.sin(t)
    image = np.where(distance > 0, STEP[1], STEP[0]).astype(np.float32)
    half = cols * texel / 2
    fov = float(mapping_of(lens)[2](half))
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


def edge_rows(lens, field: float, wavelength: float, pitch_um: float, scale, normal: str, centres: np.ndarray):
    """Where the edge crosses the image's lines along it at `centres` (mm on the image's y for an edge across
    x, x for one across y): the object's edge line traced by chief rays to the image; per line the field (deg,
    (n, 2)) of the edge's point there and the edge's position across the line (mm). On a lens whose radial
    and across scales change with field (a fisheye) the lines are not evenly spaced in field."""
    from solas_mi.optics.pupil import chief_rays

    _, coordinate, inverse = mapping_of(lens)
    t = object_tilt(scale, normal)
    s = np.linspace(-1.0, 1.0, 801) * (ALONG_PX + 2 * MARGIN_PX) * pitch_um * 1e-3 / min(scale)
    u, v = (-s * math.tan(t), coordinate(field) + s) if normal == "x" else (s, coordinate(field) + s * math.tan(t))
    xy = chief_rays(lens, np.stack([inverse(u), inverse(v)], axis=1), np.full(len(s), wavelength)).image_xy
    along = 1 if normal == "x" else 0
    order = np.argsort(xy[:, along])
    at = np.interp(centres, xy[order, along], s[order])
    u, v = (-at * math.tan(t), coordinate(field) + at) if normal == "x" else (at, coordinate(field) + at * math.tan(t))
    return np.stack([inverse(u), inverse(v)], axis=1), np.interp(at, s, xy[:, 1 - along])


def crop_centres(window: tuple[int, int, int, int], side: int, pitch_um: float) -> tuple[np.ndarray, np.ndarray]:
    """The image coordinates (mm) of the `window`'s (`windows`) pixel centres on a `side`² film: its
    columns' x and its rows' y (row 0 at +y)."""
    column, row, width, height = window
    x = (column + np.arange(width) + 0.5 - side / 2) * pitch_um * 1e-3
    y = (side / 2 - (row + np.arange(height) + 0.5)) * pitch_um * 1e-3
    return x, y


def geometric_crop(
    lens, field: float, wavelength: float, pitch_um: float, scale, normal: str, centres, texel_px: float
):
    """e-SFR MTF50s (cy/px) of the crop (pixel `centres`, `crop_centres`) built from the geometric spots (the
    ray spot, RAYS² on the entrance grid: what the render traces) of the edge's points (`edge_rows`) every
    1/SUBPIXELS pixel along it (`crop_image`), and of the same crop with every point the field's spot, and
    the fields (deg) of the edge's points within the crop: e-SFR's supersampled profile is not the rows'
    mean OTF (module docstring)."""
    from solas_mi.metrics.esfr import esfr
    from solas_mi.optics.pupil import chief_rays
    from solas_mi.psf.geometric import entrance_grid_hits

    along = 1 if normal == "x" else 0
    lines = source_lines(centres[along], pitch_um)
    fields, across = edge_rows(lens, field, wavelength, pitch_um, scale, normal, lines)
    everywhere = np.vstack([fields, [[0.0, field]]])
    wl = np.full(len(everywhere), wavelength)
    hits = entrance_grid_hits(lens, everywhere, wl, RAYS, chief_rays(lens, everywhere, wl))
    found = [
        esfr(crop_image(spots, (lines, across), centres, normal, pitch_um, texel_px))
        for spots in (hits[:-1], hits[-1:] * len(fields))
    ]
    inside = (lines >= centres[along].min()) & (lines <= centres[along].max())
    return found[0].mtf50, found[1].mtf50, np.hypot(*fields[inside].T)


def source_lines(centres: np.ndarray, pitch_um: float) -> np.ndarray:
    """Positions (mm, ascending) along the edge every 1/SUBPIXELS pixel over the crop's pixels at `centres`
    and MARGIN_PX beyond them on both sides (whence a spot's light still lands in the crop)."""
    p = pitch_um * 1e-3
    n = (len(centres) + 2 * MARGIN_PX) * SUBPIXELS
    return centres.min() - p / 2 - MARGIN_PX * p + (np.arange(n) + 0.5) * p / SUBPIXELS


def crop_image(spots, edge, centres, normal: str, pitch_um: float, texel_px: float) -> np.ndarray:
    """The crop (pixel `centres`) of the edge as the image of its bright half-plane: each of the edge's
    points at `edge` (positions along it and across, mm) lights the points of its line across the edge,
    from itself to the bright side, each through its own spot `spots` (`entrance_grid_hits`), so a row gets
    the light its spots send it from the points along the edge they come from (a spot several pixels long
    along the edge brings the blur of the fields there). Summed on a grid of SUBPIXELS points a pixel along
    the edge by ACROSS_STEPS across it, put through the texel ramp of `texel_px` across the edge, divided by
    the same image of the whole plane (the flat field) and integrated over the pixels."""
    along, p = (1 if normal == "x" else 0), pitch_um * 1e-3
    lines, across = edge
    a0, c0 = centres[along].min() - p / 2, centres[1 - along].min() - p / 2 - MARGIN_PX * p
    n_along, n_across = len(centres[along]), len(centres[1 - along])
    rows, cols = n_along * SUBPIXELS, (n_across + MARGIN_PX) * ACROSS_STEPS + 1  # the last: beyond the crop
    cells, powers = [], []
    for (x, y, power), a, c in zip(spots, lines, across):
        ra, rc = (y, x) if normal == "x" else (x, y)
        i = np.floor((a + ra * 1e-3 - a0) / (p / SUBPIXELS)).astype(int)
        j = np.clip(np.floor((c + rc * 1e-3 - c0) / (p / ACROSS_STEPS)).astype(int), 0, cols - 1)
        keep = (i >= 0) & (i < rows)
        cells.append(i[keep] * cols + j[keep])
        powers.append(power[keep])
    landed = np.bincount(np.concatenate(cells), np.concatenate(powers), rows * cols).reshape(rows, cols)
    bright = (np.cumsum(landed, axis=1) / landed.sum(axis=1, keepdims=True))[:, :-1]
    k = max(1, int(round(texel_px * ACROSS_STEPS)))
    bright = np.stack([np.convolve(np.pad(r, k, mode="edge"), np.ones(k) / k, mode="same")[k:-k] for r in bright])
    pixels = bright[:, MARGIN_PX * ACROSS_STEPS :].reshape(n_along, SUBPIXELS, n_across, ACROSS_STEPS).mean(axis=(1, 3))
    image = pixels[::-1] if normal == "x" else pixels.T[::-1]  # rows: +y first, columns: +x last
    return STEP[0] + (STEP[1] - STEP[0]) * image


def windows(point: np.ndarray, pitch_um: float, side: int) -> dict[str, tuple[int, int, int, int]]:
    """The crop windows (column, row of the corner, columns, rows) of each edge (ROI_PX across it, ALONG_PX
    along it), centred on the image `point` (mm) of a `side`² film."""
    x0 = int(round(side / 2 + point[0] * 1e3 / pitch_um))
    y0 = int(round(side / 2 - point[1] * 1e3 / pitch_um))
    return {
        "x": (x0 - ROI_PX // 2, y0 - ALONG_PX // 2, ROI_PX, ALONG_PX),
        "y": (x0 - ALONG_PX // 2, y0 - ROI_PX // 2, ALONG_PX, ROI_PX),
    }


def measure_rendered(lens, field: float, wavelength: float, pitch_um: float, directions=(0, 1)) -> list[dict]:
    """The `directions` (0: tangential, 1: sagittal) of one lens by the rendered route (module docstring),
    beside the predictions (`bench_sharpness.predicted` along the axis, `normal_mtf50` along the edge's
    normal, `geometric_crop` over the crop, and "crop": the normal's × its crop's ratio)."""
    from bench_sharpness import OVERSAMPLE, lens_psf, normal_mtf50, predicted

    from solas_mi.metrics.esfr import esfr
    from solas_mi.render.spec import RenderSpec

    point, *scale = field_point(lens, field, wavelength)
    side = int(2 * (np.abs(point).max() * 1e3 / pitch_um + ROI_PX)) // 2 * 2
    psf, _ = lens_psf(lens, field, wavelength, pitch_um / OVERSAMPLE)
    rows = []
    for direction in directions:
        normal = "yx"[direction]
        image, fov, texel_px = edge_object(lens, field, pitch_um, tuple(scale), normal)
        spec = RenderSpec(
            sensor=(side, side),
            pitch_um=pitch_um,
            fov_deg=fov,
            mapping=mapping_of(lens)[0],
            response=f"mono:{wavelength!r}",
            spp=SPP,
            rings=RINGS,
        )
        crop = windows(point, pitch_um, side)[normal]
        (flat,), seconds = render_crop(lens, np.ones((2, 2), np.float32), spec, crop, SEEDS[:1])
        edges, took = render_crop(lens, image, spec, crop, SEEDS)
        found = [esfr(e / flat) for e in edges]
        values = [r.mtf50 if r.valid else math.nan for r in found]
        along = normal_mtf50(psf, pitch_um, direction, texel_px)
        over_rows, one_field, row_fields = geometric_crop(
            lens, field, wavelength, pitch_um, tuple(scale), normal, crop_centres(crop, side, pitch_um), texel_px
        )
        rows.append(
            {
                "lens": lens.name,
                "direction": ("tangential", "sagittal")[direction],
                "texel_px": texel_px,
                "expected": predicted(lens, field, wavelength, pitch_um, direction, texel_px)[1],
                "normal": along,
                "rows": over_rows,
                "crop": along * over_rows / one_field,
                "fields": (row_fields.min(), row_fields.max()),
                "tilt": found[0].angle_deg or 0.0,  # the measured tilt from its axis
                "esfr": float(np.mean(values)),
                "spread": abs(values[0] - values[-1]),
                "reason": "; ".join(r.reason for r in found if not r.valid),
                "seconds": seconds + took,
            }
        )
    return rows
