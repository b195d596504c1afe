"""The tolerances of the lens as built (`optics.tolerance`'s kinds in `AS_BUILT`): an element's decentre
and tilt and the sensor's tilt, each as coordinate breaks (`placement.Placement`) of the drawn lens.

An element (a group of consecutive surfaces) moves rigidly: decentred by (x, y) mm along its first
surface's own x and y axes, tilted about its first surface's vertex (the pivot of Zemax's TETX/TETY: the
vertex of the group's first surface) by `tilt_x` degrees about that surface's x axis, then `tilt_y` about
the new y axis (a right-hand turn: `Placement`'s convention). The surfaces after it stay where the design
puts them. The sensor tilts about its axial point (where the last thickness reaches the image plane).

The moved frames are written back as breaks (`placed`): an element's first surface, and the surface after
it (or the image plane), gets the break (order 0) that takes its predecessor's frame to its own, and the predecessor's
thickness becomes the distance along the predecessor's axis to that break (a break has no z decentre),
as a return coordinate break with its dummy thickness does in Zemax."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .placement import Placement, frames

AS_BUILT = ("decentre", "tilt", "sensor_tilt")  # the kinds drawn as a lens as built
AXES = ("x", "y")  # each as-built kind is two terms: along (about) x and y, drawn independently


def _break(previous: tuple, target: tuple) -> tuple[float, Placement]:
    """(the predecessor's thickness, the order-0 break) that take frame `previous` to `target` (origin, axes)."""
    (o0, a0), (o1, a1) = previous, target
    local = a0.T @ (o1 - o0)
    m = a0.T @ a1  # = Rx(a) Ry(b) Rz(c) (`Placement.rotation`, order 0)
    b = math.degrees(math.asin(max(-1.0, min(1.0, m[0, 2]))))
    a = math.degrees(math.atan2(-m[1, 2], m[2, 2]))
    c = math.degrees(math.atan2(-m[0, 1], m[0, 0]))
    return float(local[2]), Placement(float(local[0]), float(local[1]), a, b, c)


def placed(lens, groups: dict, sensor: tuple[float, float] = (0.0, 0.0)):
    """`lens` as built: each element `groups[(first, last)]` (0-based surfaces) = (decentre x, y mm, tilt x,
    y degrees) moved rigidly (module docstring), the sensor tilted by `sensor` (x, y degrees)."""
    design = frames(lens.surfaces, lens.image_placement)
    target, changed = list(design), set()
    for (first, last), (dx, dy, tx, ty) in groups.items():
        pivot, axes = design[first]
        turn = axes @ Placement(tilt_x=tx, tilt_y=ty).rotation() @ axes.T
        shift = axes @ np.array([dx, dy, 0.0])
        for k in range(first, last + 1):
            origin, own = design[k]
            target[k] = (pivot + shift + turn @ (origin - pivot), turn @ own)
        changed |= {first, last + 1}  # inside an element the relative frames stay: its own breaks hold
    if any(sensor):
        origin, own = design[-1]
        target[-1] = (origin, own @ Placement(tilt_x=sensor[0], tilt_y=sensor[1]).rotation())
        changed.add(len(lens.surfaces))
    surfaces, image = list(lens.surfaces), lens.image_placement
    for k in sorted(changed):
        previous = target[k - 1] if k else (np.zeros(3), np.eye(3))
        thickness, brk = _break(previous, target[k])
        if k:
            surfaces[k - 1] = replace(surfaces[k - 1], thickness=thickness)
        if k == len(surfaces):
            image = brk
        else:
            surfaces[k] = replace(surfaces[k], placement=brk)
    return replace(lens, surfaces=tuple(surfaces), image_placement=image)


def is_as_built(spec) -> bool:
    """Whether tolerance spec `spec` draws lenses as built (a decentre, tilt or sensor tilt)."""
    return any(term.kind in AS_BUILT for term in spec.terms)


def moves(spec, deltas) -> tuple[dict, tuple[float, float]]:
    """(groups, sensor) of `placed` from the as-built terms of `spec` at `deltas`."""
    groups: dict = {}
    sensor = [0.0, 0.0]
    for term, delta in zip(spec.terms, deltas):
        if not delta:
            continue
        if term.kind == "sensor_tilt":
            sensor[AXES.index(term.axis)] += delta
        elif term.kind in AS_BUILT:
            move = groups.setdefault((term.surface, term.last), [0.0, 0.0, 0.0, 0.0])
            move[AXES.index(term.axis) + 2 * (term.kind == "tilt")] += delta
    return groups, (sensor[0], sensor[1])


def parameter(lens, term) -> float:
    """What as-built `term` moves, read back from `lens`'s frames: its first vertex's x or y (mm, decentre),
    the angle (degrees) its first surface's axis (the image plane's for the sensor) turns about x or y."""
    built = frames(lens.surfaces, lens.image_placement)
    origin, axes = built[-1 if term.surface is None else term.surface]
    if term.kind == "decentre":
        return float(origin[AXES.index(term.axis)])
    z = axes[:, 2]
    return math.degrees(-math.asin(z[1]) if term.axis == "x" else math.atan2(z[0], z[2]))


__all__ = ["AS_BUILT", "AXES", "is_as_built", "moves", "parameter", "placed"]
