"""A procedural street, written as a Mitsuba scene (`scenes/street/street.xml` and its textures): a
road with lane markings and kerbs, pavements, buildings with windows, shop signs and road signs,
office blocks closing the street, parked cars, poles and pedestrians from a few metres to ~140 m,
under a uniform sky.

Every surface is an area emitter with a grey radiance (a constant or a bitmap texture, read raw: byte
value / 255) and a black BSDF, rendered with `path` at max_depth 1: what the camera sees is the
texture itself, without shading noise, so edges are as crisp as a synthetic simulator's and a render
converges in a few samples per pixel. Textures are drawn with numpy; object placement comes from a
seeded generator, so writing the scene twice gives the same bytes. Grey radiances make the scene the
same at every wavelength: the lens alone makes the channels differ.

World: metres, y up, the street along +z from the camera at z = 0, the road between x = ±ROAD_HALF_M.
The sensor is a `perspective` camera whose pose and field are <default>s ($origin, $target, $up,
$fov: degrees across the width; $width, $height, $spp), so one file serves every framing
(`framings.framing`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

SEED = 15
TEXEL_M = 0.1  # facade texture resolution (m per texel): window edges on texel borders
ROAD_HALF_M = 5.0
KERB_M = (0.2, 0.15)  # width, height
PAVEMENT_M = 3.0
STREET_END_M = 140.0  # the buildings closing the street stand here
SKY = 0.8
ROAD, MARKING, KERB, PAVEMENT = 0.1, 0.75, 0.45, 0.3
TEXTURES = "textures"


@dataclass(frozen=True)
class Shape:
    """One emitting shape: Mitsuba type, transform (XML lines), radiance (a grey value or a texture file),
    and its name (its `id` in the scene: labels box the named shapes; the street's objects have one)."""

    kind: str
    transform: tuple[str, ...]
    radiance: float | str
    extra: tuple[str, ...] = ()
    name: str = ""


def _f(v: float) -> str:
    return f"{v:.4f}".rstrip("0").rstrip(".") if v != 0 else "0"


def _box(centre, size, yaw_deg: float = 0.0) -> tuple[str, ...]:
    """Transform of Mitsuba's cube ([-1, 1]³) to a box of `size` (m) at `centre`, turned by yaw about y."""
    sx, sy, sz = (0.5 * s for s in size)
    return (
        f'<scale x="{_f(sx)}" y="{_f(sy)}" z="{_f(sz)}"/>',
        f'<rotate y="1" angle="{_f(yaw_deg)}"/>',
        f'<translate x="{_f(centre[0])}" y="{_f(centre[1])}" z="{_f(centre[2])}"/>',
    )


def _panel(centre, size, normal: str, yaw_deg: float = 0.0) -> tuple[str, ...]:
    """Transform of Mitsuba's rectangle ([-1, 1]² in xy, facing +z) to a w×h panel facing `normal`
    ("+x", "-x", "-z", "+y": texture upright, its u along the panel's width)."""
    w, h = 0.5 * size[0], 0.5 * size[1]
    turn = {
        "+x": ('<rotate y="1" angle="90"/>',),
        "-x": ('<rotate y="1" angle="-90"/>',),
        "-z": ('<rotate y="1" angle="180"/>',),
        "+y": ('<rotate x="1" angle="-90"/>',),
    }[normal]
    return (
        f'<scale x="{_f(w)}" y="{_f(h)}"/>',
        *turn,
        f'<rotate y="1" angle="{_f(yaw_deg)}"/>',
        f'<translate x="{_f(centre[0])}" y="{_f(centre[1])}" z="{_f(centre[2])}"/>',
    )


def _cylinder(p0, p1, radius: float) -> tuple[str, ...]:
    """Properties of Mitsuba's cylinder from p0 to p1 (m) of `radius` (m)."""
    return (_point("p0", p0), _point("p1", p1), f'<float name="radius" value="{_f(radius)}"/>')


def _point(name: str, p) -> str:
    """A named <point> at p (m)."""
    return f'<point name="{name}" x="{_f(p[0])}" y="{_f(p[1])}" z="{_f(p[2])}"/>'


def facade(rng: np.random.Generator, width_m: float, height_m: float) -> np.ndarray:
    """A facade texture (rows top first, values 0–1): wall, a grid of windows of four panes per floor, a shop band
    with sign lettering on the ground floor."""
    rows, cols = round(height_m / TEXEL_M), round(width_m / TEXEL_M)
    wall = rng.choice([0.35, 0.45, 0.55, 0.62])
    tex = np.full((rows, cols), wall)
    floor = int(rng.choice([30, 32, 35]))  # texels per floor
    win_w, win_h, pitch = int(rng.integers(7, 11)), int(rng.integers(12, 16)), int(rng.integers(15, 20))
    first = (cols - ((cols - win_w) // pitch) * pitch - win_w) // 2
    for top in range(rows - floor, floor - 1, -floor):  # from the ground floor's top upwards, ground floor apart
        y0 = rows - top - floor + (floor - win_h) // 2
        if y0 < 3:
            break
        for x0 in range(first, cols - win_w + 1, pitch):
            tex[y0 : y0 + win_h, x0 : x0 + win_w] = rng.choice([0.05, 0.08, 0.12, 0.2])
            tex[y0 : y0 + win_h, x0 + win_w // 2] = min(0.9, wall + 0.25)  # mullion and transom: panes
            tex[y0 + win_h // 3, x0 : x0 + win_w] = min(0.9, wall + 0.25)
            tex[y0 + win_h : y0 + win_h + 1, x0 - 1 : x0 + win_w + 1] = min(0.9, wall + 0.25)  # sill
    band = slice(rows - floor + 4, rows - floor + 12)  # shop sign band with block letters
    tex[band, 2:-2] = 0.08
    x = 6
    while x < cols - 8:
        w = int(rng.integers(3, 6))
        tex[band.start + 2 : band.stop - 2, x : x + w] = 0.7
        x += w + int(rng.integers(2, 5))
    for x0 in range(first, cols - 12, 3 * pitch):  # shop windows and doors
        tex[rows - floor + 15 : rows - 1, x0 : x0 + 12] = 0.1
    return tex


def office(rng: np.random.Generator, width_m: float, height_m: float) -> np.ndarray:
    """An office block's facade texture: a dense grid of windows (0.5 × 0.7 m at a 0.8 × 1.0 m pitch)."""
    rows, cols = round(height_m / TEXEL_M), round(width_m / TEXEL_M)
    tex = np.full((rows, cols), 0.6)
    for y0 in range(2, rows - 12, 10):
        for x0 in range(2, cols - 6, 8):
            tex[y0 : y0 + 7, x0 : x0 + 5] = rng.choice([0.06, 0.1, 0.16, 0.24])
    return tex


def sign(kind: str) -> np.ndarray:
    """A 64×64 road-sign texture: "parking" (a P on a dark square), "warning" (a dark triangle on light),
    "stripes" (slanted bars, 30°)."""
    n = 64
    y, x = np.mgrid[0:n, 0:n] + 0.5
    tex = np.full((n, n), 0.75)
    if kind == "parking":
        tex[4:-4, 4:-4] = 0.08
        tex[14:52, 20:28] = 0.75
        tex[14:20, 20:42] = 0.75
        tex[32:38, 20:42] = 0.75
        tex[14:38, 38:44] = 0.75
    elif kind == "warning":
        inside = (y > 10) & (y < 56) & (np.abs(x - 32) < (y - 10) * 0.62)
        tex[inside] = 0.1
    else:
        tex[(((x + y * math.tan(math.radians(30))) // 10) % 2).astype(bool)] = 0.1
    return tex


def _street_layout(rng: np.random.Generator) -> tuple[list[Shape], dict[str, np.ndarray]]:
    """All shapes and the textures they use (file name → array)."""
    shapes: list[Shape] = []
    textures: dict[str, np.ndarray] = {f"sign_{k}.png": sign(k) for k in ("parking", "warning", "stripes")}
    length = STREET_END_M + 10
    shapes.append(Shape("rectangle", _panel((0, 0, length / 2), (2 * ROAD_HALF_M, length), "+y"), ROAD))
    shapes.extend(
        Shape("rectangle", _panel((0, 0.005, z + 1.5), (0.15, 3.0), "+y"), MARKING)
        for z in np.arange(4.0, STREET_END_M, 6.0)
    )  # dashed centre line
    for side in (-1, 1):
        edge = side * (ROAD_HALF_M - 0.4)
        shapes.append(Shape("rectangle", _panel((edge, 0.005, length / 2), (0.15, length), "+y"), MARKING))
        kerb_x = side * (ROAD_HALF_M + KERB_M[0] / 2)
        shapes.append(Shape("cube", _box((kerb_x, KERB_M[1] / 2, length / 2), (KERB_M[0], KERB_M[1], length)), KERB))
        walk_x = side * (ROAD_HALF_M + KERB_M[0] + PAVEMENT_M / 2)
        shapes.append(Shape("rectangle", _panel((walk_x, KERB_M[1], length / 2), (PAVEMENT_M, length), "+y"), PAVEMENT))
        front = side * (ROAD_HALF_M + KERB_M[0] + PAVEMENT_M)
        z = 2.0
        while z < STREET_END_M - 6:  # buildings along the street, facades facing it
            w = float(rng.uniform(12, 24))
            h = float(rng.choice([9.6, 12.8, 16.0, 19.2]))
            name = f"facade_{len(textures):02d}.png"
            textures[name] = facade(rng, w, h)
            depth = 12.0
            shapes.append(
                Shape(
                    "cube",
                    _box((front + side * depth / 2, h / 2, z + w / 2), (depth, h, w)),
                    float(rng.choice([0.25, 0.3, 0.4])),
                )
            )
            shapes.append(
                Shape(
                    "rectangle",
                    _panel((front - side * 0.02, h / 2, z + w / 2), (w, h), "-x" if side > 0 else "+x"),
                    name,
                )
            )
            z += w + float(rng.uniform(0.0, 3.0))
    for x_c in (-12.0, 8.0):  # the buildings closing the street, facing the camera
        w, h = 20.0, 16.0
        name = f"facade_{len(textures):02d}.png"
        textures[name] = office(rng, w, h)
        shapes.append(Shape("cube", _box((x_c, h / 2, STREET_END_M + 6), (w, h, 12)), 0.3))
        shapes.append(Shape("rectangle", _panel((x_c, h / 2, STREET_END_M - 0.02), (w, h), "-z"), name))
    _street_furniture(rng, shapes)
    return shapes, textures


def _street_furniture(rng: np.random.Generator, shapes: list[Shape]) -> None:
    """Parked cars, poles with signs and pedestrians along both kerbs, posts on traffic islands: each
    shape named after its object (car_3_cabin, pedestrian_2_head, ...)."""
    for i, z in enumerate((7.0, 13.0, 22.0, 34.0, 48.0, 63.0, 80.0, 98.0, 118.0)):  # parked cars
        side = 1 if i % 2 == 0 else -1
        x = side * (ROAD_HALF_M - 1.1)
        yaw = float(rng.uniform(-4, 4))
        body = float(rng.choice([0.06, 0.15, 0.55, 0.7]))
        shapes.append(Shape("cube", _box((x, 0.65, z), (1.8, 0.8, 4.3), yaw), body, name=f"car_{i + 1}"))
        shapes.append(
            Shape(
                "cube",
                _box((x, 1.3, z - 0.2), (1.6, 0.55, 2.2), yaw),
                0.1 if body > 0.3 else 0.5,
                name=f"car_{i + 1}_cabin",
            )
        )
        for end, dz in (("rear", -1.4), ("front", 1.4)):
            wheel = _cylinder((x - 0.92, 0.33, z + dz), (x + 0.92, 0.33, z + dz), 0.33)
            shapes.append(Shape("cylinder", (), 0.04, wheel, name=f"car_{i + 1}_wheels_{end}"))
    for i, (x, z) in enumerate(((0.05, 20.0), (2.1, 60.0))):  # posts on traffic islands
        shapes.append(Shape("cylinder", (), 0.65, _cylinder((x, 0, z), (x, 3, z), 0.06), name=f"post_{i + 1}"))
    kinds = ("parking", "warning", "stripes")
    for i, z in enumerate(np.arange(10.0, STREET_END_M - 5, 14.0)):  # poles, every other one with a sign
        side = -1 if i % 2 == 0 else 1
        x = side * (ROAD_HALF_M + 0.6)
        shapes.append(Shape("cylinder", (), 0.12, _cylinder((x, 0, z), (x, 4.5, z), 0.06), name=f"pole_{i + 1}"))
        if i % 2 == 0:
            shapes.append(
                Shape(
                    "rectangle",
                    _panel((x, 3.6, z - 0.08), (0.8, 0.8), "-z", float(rng.uniform(-6, 6))),
                    f"sign_{kinds[i // 2 % 3]}.png",
                    name=f"pole_{i + 1}_sign_{kinds[i // 2 % 3]}",
                )
            )
    for i, z in enumerate((9.0, 17.0, 27.0, 41.0, 56.0, 72.0, 90.0, 108.0)):  # pedestrians
        side = 1 if i % 2 else -1
        x = side * (ROAD_HALF_M + 1.2 + float(rng.uniform(0, 1.5)))
        tone = float(rng.choice([0.05, 0.12, 0.6]))
        shapes.append(
            Shape("cylinder", (), tone, _cylinder((x, 0.15, z), (x, 1.45, z), 0.22), name=f"pedestrian_{i + 1}")
        )
        shapes.append(
            Shape(
                "sphere",
                (),
                0.5,
                (_point("center", (x, 1.62, z)), '<float name="radius" value="0.13"/>'),
                name=f"pedestrian_{i + 1}_head",
            )
        )


def scene_xml(shapes: list[Shape]) -> str:
    """The scene file's text: integrator, sensor (pose and field as <default>s: by default the doublet's
    framing, `framings.NARROW`, so the file as it is frames the experiment's view), sky and shapes."""
    from .framings import NARROW

    defaults = NARROW.params(4.0, 1280, 960, 16)  # the doublet's view, rolled, as the experiment renders it
    out = [
        '<scene version="3.0.0">',
        "    <!-- written by solas_mi.experiments.street.scene: regenerate, do not edit -->",
        *(
            f'    <default name="{k}" value="{defaults[k]}"/>'
            for k in ("width", "height", "spp", "fov", "origin", "target", "up")
        ),
        '    <integrator type="path"><integer name="max_depth" value="1"/></integrator>',
        '    <sensor type="perspective">',
        '        <float name="fov" value="$fov"/>',
        '        <string name="fov_axis" value="x"/>',
        '        <transform name="to_world"><lookat origin="$origin" target="$target" up="$up"/></transform>',
        '        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>',
        '        <film type="hdrfilm"><integer name="width" value="$width"/>'
        '<integer name="height" value="$height"/><rfilter type="gaussian"/></film>',
        "    </sensor>",
        f'    <emitter type="constant"><spectrum name="radiance" value="{_f(SKY)}"/></emitter>',
        '    <bsdf type="diffuse" id="black"><spectrum name="reflectance" value="0"/></bsdf>',
    ]
    for s in shapes:
        if isinstance(s.radiance, str):
            radiance = (
                f'<texture type="bitmap" name="radiance"><string name="filename" value="{TEXTURES}/'
                f'{s.radiance}"/><boolean name="raw" value="true"/><string name="filter_type" '
                'value="nearest"/><string name="wrap_mode" value="clamp"/></texture>'
            )
        else:
            radiance = f'<spectrum name="radiance" value="{_f(s.radiance)}"/>'
        out.append(f'    <shape type="{s.kind}"' + (f' id="{s.name}"' if s.name else "") + ">")
        out += [f"        {line}" for line in s.extra]
        if s.transform:
            out.append('        <transform name="to_world">' + "".join(s.transform) + "</transform>")
        out += ['        <ref id="black"/>', f'        <emitter type="area">{radiance}</emitter>', "    </shape>"]
    out.append("</scene>")
    return "\n".join(out) + "\n"


def write_street(folder: str | os.PathLike) -> list[Path]:
    """Write street.xml and its textures (8-bit grey PNG, linear values) into `folder`; returns the files.
    The same bytes every time (a seeded generator, fixed number formats)."""
    from ...imageio import write_png, write_text

    folder = Path(folder)
    shapes, textures = _street_layout(np.random.default_rng(SEED))
    written = []
    for name, tex in textures.items():
        path = folder / TEXTURES / name
        write_png(path, tex, encoded=True)
        written.append(path)
    write_text(folder / "street.xml", scene_xml(shapes))
    return [*written, folder / "street.xml"]
