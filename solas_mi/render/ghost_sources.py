"""The light sources whose ghosts `ghost_light` traces: each emitter of a scene that can send a lens
camera stray light, and the light it sends into the lens along a ray through a point of the lens's front
vertex plane.

Sources (`sources`), each seen from the camera's `to_world` (the lens frame: the camera's (x, −y, −z),
`lens_camera`; directions are those the light travels, toward the lens, +z):
- an area emitter whose bounding sphere lies in front of the lens and away from it: the cone of
  directions its sphere subtends (`CONE`);
- an environment map (`envmap`): its sun, the cone about its brightest direction holding the
  directions whose radiance is at least `SUN_SHARE` of the brightest (`SUN_PROBES` directions drawn
  from the map's own importance sampling), widened by one texel; the rest of the sky is not traced;
- a delta light (`directional`, `point`, `spot`): its one direction at each point (`DELTA`).
A constant environment (a uniform sky: no sun) and other emitters have no source (`skipped` says so).

`light(source, …)` gives, for rays through entrance points of the vertex plane, each ray's direction
and the light it carries per unit area of that plane and per wavelength: a cone's radiance seen along the
ray (a scene ray cast from the point toward the source: an occluder, or another emitter in front, gives
0) × the cone's solid angle (the ray's direction uniform in it); a delta light's irradiance at the point
(its `sample_direction`) where a shadow ray reaches it. Either × cos θ (the plane's area across the
ray).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

CONE, DELTA = "cone", "delta"
DELTA_TYPES = ("DirectionalEmitter", "PointLight", "SpotLight")  # Mitsuba's class names of its delta lights
SUN_SHARE = 0.1  # an environment's sun: its directions of radiance at least this share of the brightest
SUN_PROBES = 4096  # directions drawn from an environment map's importance sampling to find its sun


@dataclass
class Source:
    """One emitter's light toward the lens: `kind` CONE (directions uniform in the cone of half-angle
    `radius` (rad) about `axis`, lens frame) or DELTA (one direction per point); `name` for the metadata."""

    name: str
    kind: str
    emitter: object
    axis: np.ndarray
    radius: float
    environment: bool = False

    @property
    def solid_angle(self) -> float:
        return 2.0 * math.pi * (1.0 - math.cos(self.radius))


def sources(scene, to_world: np.ndarray) -> tuple[list[Source], list[str]]:
    """The `Source`s of `scene` seen by a camera at 4×4 `to_world` (module docstring), and the emitters
    without one (their class names and why)."""
    found, skipped = [], []
    to_local = np.linalg.inv(to_world)
    for emitter in scene.emitters():
        kind, shape = emitter.class_name(), emitter.get_shape()
        if shape is not None:
            box = shape.bbox()
            centre = (to_local @ np.append(np.array(box.center(), dtype=np.float64), 1.0))[:3]
            scale = np.linalg.norm(to_local[:3, :3], axis=0).mean()  # world → camera units (a rigid move: 1)
            distance, radius = float(np.linalg.norm(centre)), 0.5 * scale * float(np.linalg.norm(box.extents()))
            if centre[2] > 0 and distance > radius:
                axis = np.array([-centre[0], centre[1], centre[2]]) / distance
                found.append(Source(f"area {shape.id() or kind}", CONE, emitter, axis, math.asin(radius / distance)))
            else:
                skipped.append(f"area {shape.id() or kind} (behind the lens or around it)")
        elif kind in DELTA_TYPES:
            found.append(Source(kind, DELTA, emitter, np.array([0.0, 0.0, 1.0]), 0.0))
        elif kind == "EnvironmentMapEmitter":
            found.append(_sun(scene, emitter, to_local))
        else:
            skipped.append(f"{kind} (no sun to trace)")
    return found, skipped


def _sun(scene, emitter, to_local: np.ndarray) -> Source:
    """An environment map's sun (module docstring) as a CONE source."""
    it = dr.zeros(mi.Interaction3f, SUN_PROBES)
    it.p = mi.Point3f(scene.bbox().center())
    it.wavelengths = dr.full(mi.Spectrum, 550.0, SUN_PROBES) if mi.is_spectral else it.wavelengths
    u = (np.arange(SUN_PROBES) + 0.5) / SUN_PROBES
    ds, _ = emitter.sample_direction(it, mi.Point2f(u, np.random.default_rng(1).permutation(u)))
    si = dr.zeros(mi.SurfaceInteraction3f, SUN_PROBES)
    si.wi, si.wavelengths = -ds.d, it.wavelengths
    radiance = np.array(emitter.eval(si)[0], dtype=np.float64)
    d = np.array(ds.d, dtype=np.float64)
    sun = radiance >= SUN_SHARE * radiance.max()
    centre = (d[:, sun] * radiance[sun]).sum(axis=1)
    centre /= np.linalg.norm(centre)
    spread = float(np.arccos(np.clip(centre @ d[:, sun], -1.0, 1.0)).max())
    texel = math.pi / int(np.shape(mi.traverse(emitter)["data"])[0])
    local = to_local[:3, :3] @ centre  # toward the sun, camera frame; the light travels the other way
    local /= np.linalg.norm(local)
    return Source("envmap sun", CONE, emitter, np.array([-local[0], local[1], local[2]]), spread + texel, True)


def _lens_to_camera(v):
    """A lens-frame vector (x, y, z) in the camera frame (x, −y, −z)."""
    return mi.Vector3f(v[0], -v[1], -v[2])


def light(scene, source: Source, to_world, world_unit_mm: float, points, u, wavelengths):
    """Rays through entrance `points` (ex, ey: mi.Float, mm, lens frame) of the vertex plane from `source`
    (camera at mi.Transform4f `to_world`), their directions from uniform `u` (mi.Point2f; a CONE's): (the
    lens-frame directions, mi.Vector3f; the light each carries per mm² of the plane at `wavelengths` (a
    Mitsuba Spectrum), lane 0's, mi.Float) (module docstring)."""
    ex, ey = points
    scale = opaque(1.0 / world_unit_mm)
    p = to_world @ mi.Point3f(ex * scale, -ey * scale, 0.0)
    if source.kind == CONE:
        d = cone(source.axis, source.radius, u)
        si = scene.ray_intersect(mi.Ray3f(p, dr.normalize(to_world @ -_lens_to_camera(d)), 0.0, wavelengths))
        emitter = si.emitter(scene)
        mine = ~si.is_valid() if source.environment else (emitter == mi.EmitterPtr(source.emitter))
        value = dr.select(mine, emitter.eval(si, mine)[0] * opaque(source.solid_angle), 0.0)
    else:
        it = dr.zeros(mi.Interaction3f, dr.width(ex))
        it.p, it.wavelengths = p, wavelengths
        ds, spectrum = source.emitter.sample_direction(it, u)
        value = dr.select(scene.ray_test(it.spawn_ray_to(ds.p)), 0.0, spectrum[0])
        d = -_lens_to_camera(dr.normalize(to_world.inverse() @ ds.d))  # the camera map is its own inverse
    value = dr.select(dr.isfinite(value) & (d.z > 0), value * d.z, 0.0)
    return d, value


def cone(axis: np.ndarray, radius: float, u):
    """Unit directions uniform in the cone of half-angle `radius` about `axis` (NumPy) from uniform `u`
    (mi.Point2f)."""
    cos_t = 1.0 - u.x * opaque(1.0 - math.cos(radius))
    sin_t, phi = dr.sqrt(dr.maximum(1.0 - cos_t * cos_t, 0.0)), 2.0 * math.pi * u.y
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    a = np.cross(axis, helper)
    a /= np.linalg.norm(a)
    b = np.cross(axis, a)
    sc, ss = sin_t * dr.cos(phi), sin_t * dr.sin(phi)
    return mi.Vector3f(*(opaque(axis[k]) * cos_t + opaque(a[k]) * sc + opaque(b[k]) * ss for k in range(3)))


def opaque(value) -> mi.Float:
    """A number as an opaque mi.Float: one kernel for every source and camera."""
    return dr.opaque(mi.Float, float(value))
