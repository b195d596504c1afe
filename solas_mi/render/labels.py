"""Labels through the lens: what each pixel of a `lens_camera` render sees (`LABELS`: its distance, the
surface's orientation, which shape), found along the pixel centre's chief ray, the real ray from the
film point through the centre of the stop (`optics.aiming.film_chief_aim`, traced by the camera's own
`exit_ray`). The labels are crisp (one ray per pixel, no blur) and distorted exactly as the image is: the
same lens, the same film geometry, the same camera frame. Where an aperture blocks the chief ray but other rays of the
pixel pass (vignetting; the rim of a fisheye's image circle), the label ray is the centre of the beam
that passes (`beam_centres`), and the metadata's `beam_centre_pixels` counts those pixels.

Layers (EXR `layer.channel` names, float32, beside the image's channels; 0 where nothing is met): those
of each label of `LABELS` (a `solas_mi.registry.Registry`: a label's function of a `Hit`, its layer
names, its summary), and `labels.valid`, always: 1 where a ray of the pixel passes the lens and the label
ray meets the scene, else 0.

An instance id is a 24-bit hash of the shape's name (exact in float32, never 0), so a shape keeps its
id from frame to frame and scene to scene; the metadata's `instances` table maps each id met to its
name and `boxes` gives each named shape's pixel bounds [x0, y0, x1, y1) (columns, rows; end
exclusive), pixel count and 3D box (`boxes_3d`: its world bounding box's corners in the camera frame and
their pixels through the real lens). The chief ray is traced at the response's one wavelength, else at the
lens's primary wavelength; a pixel none of whose rays passes (past the image circle) is not valid.
No NaN or inf is written. A scene loaded with Mitsuba's default parser settings (`mi.load_file`) has
its meshes of one material merged into one unnamed mesh, and so one id: load it with
`render.user_scene.load` (as `solas-mi render` does), which keeps them apart.
"""

from __future__ import annotations

import re
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import SolasError
from ..labelkinds import ID_LIMIT, KINDS, VALID
from ..registry import Registry

# label → its function (`Hit`) -> (layer name → H×W float32, metadata), with its layer names (`layers`)
LABELS = Registry("label", shown=("layers",))
# the beams tried where a pixel's chief ray is blocked, until one passes: (film points, pupil samples) per
# side; the pixel centre's with a coarse and then a fine pupil grid (a sliver of a beam at the edge of the
# field), then from points across the pixel (a pixel at the rim of a fisheye's image circle)
BEAMS = ((1, 8), (1, 24), (4, 8))
ID_MASK = ID_LIMIT - 1  # ids below 2^24: exact in a float32 channel
# memory per pixel (bytes), measured at 2560×1920 through wide-angle-22mm (peak RSS over a render without
# labels): the label rays' trace and scene intersection, and each channel (labels.valid and the layers')
LABEL_RAY_BYTES, LABEL_CHANNEL_BYTES = 100, 6


def parse_labels(given) -> tuple[str, ...]:
    """The labels of a comma-separated list ("depth,instance") or a sequence of names, in `LABELS` order;
    () for None or ""."""
    text = given if isinstance(given, str) or given is None else ",".join(map(str, given))
    names = [t.strip().lower() for t in (text or "").split(",") if t.strip()]
    bad = [n for n in names if n not in LABELS]
    if bad:
        raise SolasError(f"labels {', '.join(map(repr, bad))} must be among {', '.join(LABELS)} (comma-separated)")
    return tuple(n for n in LABELS if n in names)


def memory_bytes(pixels: int, kinds) -> int:
    """Memory (bytes) that tracing the label layers `kinds` (as `parse_labels` reads them) of a film of
    `pixels` adds to its render: 0 for none (measured: depth +112 B per pixel, all three +132)."""
    kinds = parse_labels(kinds)
    if not kinds:
        return 0
    channels = 1 + sum(len(LABELS[k].extra["layers"]) for k in kinds)
    return pixels * (LABEL_RAY_BYTES + LABEL_CHANNEL_BYTES * channels)


def instance_id(name: str) -> int:
    """A shape's instance id: CRC-32 of its name in 24 bits, 0 (the background's) mapped to 1."""
    return (zlib.crc32(name.encode("utf-8")) & ID_MASK) or 1


def is_instance(shape) -> bool:
    """Whether `shape` (of `scene.shapes()`) is an `instance` of a `shapegroup`: a ray that meets it
    meets one of the group's shapes, which `si.shape` names, and the instance is `si.instance`."""
    return shape.class_name() == "Instance"


def _group(instance) -> str:
    """The id of the shapegroup an instance places, as Mitsuba describes the instance ("" if it names
    none: Mitsuba's Python interface has no getter for it)."""
    found = re.search(r'ShapeGroup\[\s*name = "([^"]*)"', str(instance))
    return found.group(1) if found else ""


def shape_names(scene) -> list[str]:
    """Each shape's name: its `id`, or for an unnamed one `_shape_<key>` (an unnamed instance
    `_instance_<group>_<key>`, `group` its shapegroup's id), `key` a hash of its world bounding box
    (5 significant digits) and primitive count, with `#2`, `#3`, … for unnamed shapes alike in both. Not
    the shape's place in `scene.shapes()`: that order differs between the LLVM and CUDA variants (and may
    between loads), and with it the ids of a frame."""
    names, seen = [], {}
    for shape in scene.shapes():
        if shape.id():
            names.append(shape.id())
            continue
        box = shape.bbox()
        key = ",".join(f"{float(v):.5g}" for v in (*box.min, *box.max)) + f";{shape.primitive_count()}"
        kind = f"instance_{_group(shape)}" if is_instance(shape) else "shape"
        base = f"_{kind}_{zlib.crc32(key.encode('ascii')):08x}"
        seen[base] = seen.get(base, 0) + 1
        names.append(base if seen[base] == 1 else f"{base}#{seen[base]}")
    return names


def _instance_ids(names: list[str]) -> list[int]:
    """The ids of `names`; a SolasError where two names share one."""
    ids, seen = [instance_id(n) for n in names], {}
    for name, i in zip(names, ids):
        if seen.setdefault(i, name) != name:
            raise SolasError(f"shapes {seen[i]!r} and {name!r} hash to the same instance id {i}: rename one")
    return ids


def _sensor(scene):
    import drjit as dr
    import mitsuba as mi

    sensor = scene.sensors()[0]
    if type(sensor).__name__ != "LensCamera":
        raise SolasError(
            f"labels are traced through a lens_camera; the scene's sensor is {type(sensor).__name__} "
            "(render with --lens)"
        )
    if not dr.is_jit_v(mi.Float):
        raise SolasError(f"labels need a vectorised Mitsuba variant (llvm_ad_*, cuda_ad_*), not {mi.variant()}")
    return sensor


def chief_rays(sensor):
    """The label ray of each pixel of `sensor` (a `lens_camera`; row-major over its crop window), leaving
    surface 1: origin, direction (camera frame, world units), whether it passed, the wavelength, and how
    many pixels took their beam's centre (`beam_centres`) for a blocked chief ray."""
    import drjit as dr
    import mitsuba as mi

    from ..optics.aiming import film_chief_aim

    w, h = sensor.width, sensor.height
    i = dr.arange(mi.UInt32, w * h)
    film = sensor.film_point(mi.Point2f((mi.Float(i % w) + 0.5) / w, (mi.Float(i // w) + 0.5) / h))
    lam = sensor.response.single_wavelength or sensor.lens.primary_wavelength
    x, y = (np.asarray(v, dtype=np.float64) for v in (film.x, film.y))
    ex, ey, found = film_chief_aim(sensor.reversed, x, y, lam)
    ex, ey = np.where(found, ex, 0.0), np.where(found, ey, 0.0)
    chief = sensor.exit_ray(film, mi.Point2f(ex, ey), mi.Float(lam))
    passed = found & np.asarray(chief[2])
    start_x, start_y, through_chief = x.copy(), y.copy(), passed.copy()  # where each label ray leaves the film
    for film_side, pupil_side in BEAMS:  # a blocked chief ray: the centre of the beam that passes
        spread = sensor.pitch_mm if film_side > 1 else 0.0
        todo = np.flatnonzero(~passed & _may_pass(sensor, x, y, spread))
        *centre, through = beam_centres(sensor, x[todo], y[todo], lam, (film_side, pupil_side), spread)
        for values, got in zip((start_x, start_y, ex, ey), centre):
            values[todo[through]] = got[through]
        passed[todo] = through
    centred = int(passed.sum() - through_chief.sum())
    if centred:
        chief = sensor.exit_ray(mi.Point2f(start_x, start_y), mi.Point2f(ex, ey), mi.Float(lam))
    return chief[0], chief[1], chief[2] & mi.Bool(passed), lam, centred


def _may_pass(sensor, x: np.ndarray, y: np.ndarray, spread: float) -> np.ndarray:
    """Whether a film point of the square `spread` mm wide (a pixel, for its pitch) about (x, y) may lie
    at a film radius that the exit-pupil bounds say light reaches."""
    bounds = sensor.pupil.bounds
    area = (bounds.bounds_mm[:, 1] - bounds.bounds_mm[:, 0]) * (bounds.bounds_mm[:, 3] - bounds.bounds_mm[:, 2])
    lit = np.flatnonzero(area > 0.0)
    if len(lit) == 0:
        return np.zeros(len(x), dtype=bool)
    reach = bounds.radius_mm[min(lit.max() + 1, len(bounds.radius_mm) - 1)]
    return np.hypot(x, y) - spread / np.sqrt(2.0) <= reach


def beam_centres(sensor, x: np.ndarray, y: np.ndarray, lam: float, sides: tuple[int, int], spread: float = 0.0):
    """For film points (x, y) mm whose chief ray is blocked, the ray through the centre of the beam that
    passes: its film point, its point on the plane `sensor.pupil` samples (mm), and whether any ray
    passes. The beam: sides[1]² pupil samples from each of sides[0]² film points over a square `spread`
    mm wide (for one, the point itself). Its centre is the centroid of the passing rays' film and
    pupil points, each ray weighted as the render weighs it (pupil weight × transmittance): the mean of
    the rays that make the pixel's image, so an edge's place in the image (the centroid of its blur) is
    where that ray meets it. Where the centroid's own ray is blocked (a beam that is not convex), the
    passing sample nearest it stands in."""
    out = [np.zeros(len(x)) for _ in range(4)] + [np.zeros(len(x), dtype=bool)]
    chunk = max(1, (1 << 21) // (sides[0] * sides[1]) ** 2)
    for start in range(0, len(x), chunk):
        part = slice(start, start + chunk)
        for values, got in zip(out, _beam_centres(sensor, x[part], y[part], lam, spread, sides)):
            values[part] = got
    return tuple(out)


def _grid(side: int) -> tuple[np.ndarray, np.ndarray]:
    """Cell centres of a side × side grid over [0, 1]², raveled."""
    u = (np.arange(side) + 0.5) / side
    return tuple(a.ravel() for a in np.meshgrid(u, u))


def _beam_centres(sensor, x, y, lam, spread, sides):
    """`beam_centres` of one chunk of film points."""
    import drjit as dr
    import mitsuba as mi

    n = len(x)
    (fu, fv), (su, sv) = _grid(sides[0]), _grid(sides[1])
    k = len(su)
    shape = (n, len(fu) * k)
    fx = (np.repeat(x, len(fu) * k) + np.tile(np.repeat(fu - 0.5, k), n) * spread).reshape(shape)
    fy = (np.repeat(y, len(fu) * k) - np.tile(np.repeat(fv - 0.5, k), n) * spread).reshape(shape)
    film = mi.Point2f(fx.ravel(), fy.ravel())
    target, weight = sensor.pupil.sample(film, mi.Point2f(np.tile(su, n * len(fu)), np.tile(sv, n * len(fu))))
    passed, transmittance = sensor.exit_ray(film, target, mi.Float(lam))[2:]
    wt = np.asarray(dr.select(passed, weight * transmittance, 0.0), dtype=np.float64).reshape(shape)
    px, py = (np.asarray(v, dtype=np.float64).reshape(shape) for v in (target.x, target.y))
    total = wt.sum(axis=1)
    through = total > 0.0
    centre = [(wt * v).sum(axis=1) / np.where(through, total, 1.0) for v in (fx, fy, px, py)]
    centre_passes = np.asarray(sensor.exit_ray(mi.Point2f(*centre[:2]), mi.Point2f(*centre[2:]), mi.Float(lam))[2])
    far = sum(np.square(v - c[:, None]) for v, c in zip((fx, fy, px, py), centre))
    nearest = np.argmin(np.where(wt > 0.0, far, np.inf), axis=1)
    rows = np.arange(n)
    return [np.where(centre_passes, c, v[rows, nearest]) for c, v in zip(centre, (fx, fy, px, py))] + [through]


@dataclass(frozen=True)
class Hit:
    """What each pixel's label ray met: the scene, Mitsuba's surface interaction, the camera's world
    transform, the entrance pupil's z in the camera frame (world units), and `layer`, which makes a value
    per ray an H×W float32 layer (0 where the label is not valid)."""

    scene: Any
    si: Any
    to_world: Any
    pupil_z: float
    layer: Callable


def render_labels(scene, kinds) -> tuple[dict[str, np.ndarray], dict]:
    """The label layers `kinds` (of `LABELS`, as `parse_labels` reads them) of a scene seen by its
    `lens_camera`, each H×W float32, with `labels.valid`, and their metadata (module docstring)."""
    import drjit as dr
    import mitsuba as mi

    sensor = _sensor(scene)
    kinds = parse_labels(kinds)
    origin, direction, passed, lam, centred = chief_rays(sensor)
    to_world = sensor.world_transform()
    si = scene.ray_intersect(mi.Ray3f(to_world @ origin, to_world @ direction), passed)
    valid = passed & si.is_valid()
    size = (sensor.height, sensor.width)

    def layer(value):
        return np.asarray(dr.select(valid, value, 0.0), dtype=np.float32).reshape(size)

    layers = {VALID: layer(mi.Float(1.0))}
    pupil_z = -float(_entrance_pupil_mm(sensor.lens)) / sensor.world_unit_mm  # camera frame: +z toward the scene
    meta = {
        "kinds": list(kinds),
        "wavelength_nm": float(lam),
        "depth": "range (world units) from the entrance-pupil centre to the point the pixel centre's chief "
        "ray (where it is blocked, the passing beam's centre ray) meets; 0 where labels.valid is 0",
        "entrance_pupil_z": pupil_z,
        "beam_centre_pixels": centred,
    }
    hit = Hit(scene, si, to_world, pupil_z, layer)
    for kind in kinds:
        more, about = LABELS[kind].function(hit)
        layers.update(more)
        meta.update(about)
    meta["layers"] = sorted(layers)
    return layers, meta


@LABELS.register(
    "depth",
    layers=KINDS["depth"].extra["layers"],
    summary="range, in world units: the distance from the centre of the lens's paraxial entrance "
    "pupil (on the axis, `entrance_pupil_z` world units in front of surface 1's vertex in the "
    "metadata; negative: behind it) to the point the chief ray meets",
)
def _depth(hit: Hit):
    import drjit as dr
    import mitsuba as mi

    (name,) = LABELS["depth"].extra["layers"]
    return {name: hit.layer(dr.norm(hit.si.p - hit.to_world @ mi.Point3f(0.0, 0.0, hit.pupil_z)))}, {}


@LABELS.register(
    "normal",
    layers=KINDS["normal"].extra["layers"],
    summary="the unit shading normal there, in the world frame, as Mitsuba gives it (not turned toward the camera)",
)
def _normal(hit: Hit):
    n = hit.si.sh_frame.n
    return {name: hit.layer(v) for name, v in zip(LABELS["normal"].extra["layers"], (n.x, n.y, n.z))}, {}


@LABELS.register(
    "instance",
    layers=KINDS["instance"].extra["layers"],
    summary="the shape's id, `instance_id` of its name (its `id` in the scene; an unnamed shape "
    "`_shape_<key>`, a hash of its bounding box and primitive count); the shapes of a `shapegroup` "
    "take the id of the `instance` that places them, one id per instance (an unnamed one "
    "`_instance_<group>_<key>`)",
)
def _instance(hit: Hit):
    import drjit as dr
    import mitsuba as mi

    names = shape_names(hit.scene)
    ids = _instance_ids(names)
    value = mi.Float(0.0)
    for item, i in zip(hit.scene.shapes(), ids):  # a shapegroup's shape takes the id of the instance met
        met = hit.si.instance if is_instance(item) else hit.si.shape
        value = dr.select(met == mi.ShapePtr(item), float(i), value)
    layer = hit.layer(value)
    about = _instances(layer, names, ids, hit.scene)
    boxes_3d(hit, about["boxes"], dict(zip(names, hit.scene.shapes())))
    (name,) = LABELS["instance"].extra["layers"]
    return {name: layer}, about


def boxes_3d(hit: Hit, boxes: dict, shapes: dict) -> None:
    """Each named shape's 3D box beside its 2D one: the 8 corners of its world bounding box in the camera frame
    of the calibration files (x right, y down, z forward; world units, from the entrance pupil's centre) and
    their pixels through the real lens (`optics.calibration`: the lens's chief-ray mapping over the film; None
    for a corner behind the lens or beyond the film's widest direction), corner k at (x, y, z) = box (min, max)[bits of k]."""
    import mitsuba as mi

    from ..optics.calibration import Sensor, chief_map

    if not boxes:
        return
    sensor = _sensor(hit.scene)
    cmap = chief_map(
        sensor.lens,
        Sensor(int(sensor.width), int(sensor.height), float(sensor.pitch_um)),
        float(sensor.response.single_wavelength or sensor.lens.primary_wavelength),
    )
    to_local = hit.to_world.inverse()
    for name, box in boxes.items():
        b = shapes[name].bbox()
        lo, hi = [float(v) for v in b.min], [float(v) for v in b.max]
        corners = np.array([[(lo, hi)[(k >> a) & 1][a] for a in range(3)] for k in range(8)])
        local = to_local @ mi.Point3f(*corners.T)
        xyz = np.stack([-np.asarray(local.x), -np.asarray(local.y), np.asarray(local.z) - hit.pupil_z], -1)
        unit = xyz / np.linalg.norm(xyz, axis=1, keepdims=True)
        uv = cmap.pixels(unit)
        polar = np.arccos(np.clip(unit[:, 2], -1.0, 1.0))
        seen = (polar <= cmap.top) & np.isfinite(uv).all(axis=1)
        box["box_3d"] = {
            "corners_camera": xyz.tolist(),
            "corners_px": [p.tolist() if ok else None for p, ok in zip(uv, seen)],
        }


def _entrance_pupil_mm(lens) -> float:
    """The paraxial entrance pupil's distance behind surface 1's vertex (mm, along the lens's axis)."""
    from ..optics.paraxial import paraxial

    return paraxial(lens).entrance_pupil_z_mm - float(lens.vertex_z[0])


def _instances(ids: np.ndarray, names: list[str], id_list: list[int], scene) -> dict:
    """The `instances` table (id → name) of the ids met, and `boxes` of the named shapes met."""
    met = set(np.unique(ids).astype(np.int64).tolist()) - {0}
    table, boxes = {}, {}
    for shape, name, i in zip(scene.shapes(), names, id_list):
        if i not in met:
            continue
        table[str(i)] = name
        if shape.id():
            rows, cols = np.nonzero(ids == i)
            boxes[name] = {
                "id": i,
                "box": [int(cols.min()), int(rows.min()), int(cols.max()) + 1, int(rows.max()) + 1],
                "pixels": int(len(rows)),
            }
    return {"instances": table, "boxes": boxes}
