"""Where a surface sits: a coordinate break before it (`Placement`), in Zemax's COORDBRK convention.
The break moves the coordinate frame in which this surface and every one after it lie (their vertices
follow along the new z axis, `thickness` by `thickness`, to the image plane): with `order` 0 it decentres
by (`decentre_x`, `decentre_y`) along the current x and y axes, then tilts by `tilt_x` degrees about the
x axis, then `tilt_y` about the new y axis, then `tilt_z` about the newest z axis; with `order` 1 it tilts
about z, then y, then x, then decentres along the tilted axes (so a break of order 1 with every value
negated undoes one of order 0). Each tilt turns the frame by the right-hand rule: a positive `tilt_x`
turns +y toward +z. (OpticStudio User Guide, "Coordinate Break" and "Tilt/Decenter": "decentered in X,
decentered in Y, and then tilted around X, tilted around Y, tilted around Z … tilts in degrees about the
respective axis in a right hand direction", the order flag reversing the sequence.)

`frames` chains the breaks of a lens: each surface's vertex and axes, and the image plane's, in the
global frame of surface 1 (the lens as built). Lengths in mm, angles in degrees.
"""

from __future__ import annotations

import math
from dataclasses import astuple, dataclass, fields, replace

import numpy as np

from ..errors import SolasError

ORDERS = (0, 1)  # Zemax's order flag: 0 decentre then tilt x, y, z; 1 tilt z, y, x then decentre
FACING_LIMIT = 90.0
"""|tilt_x| and |tilt_y| stay below it (degrees): the new z axis keeps cos(tilt_x)·cos(tilt_y) > 0 of the old one,
in either order; at 90° or more the surface turns edge-on or backward."""
SPIN_LIMIT = 360.0
"""|tilt_z| at most it (degrees): a spin about the axis, a full turn at most."""


@dataclass(frozen=True)
class Placement:
    """A coordinate break: decentres (mm), tilts (degrees) and the order flag (`ORDERS`)."""

    decentre_x: float = 0.0
    decentre_y: float = 0.0
    tilt_x: float = 0.0
    tilt_y: float = 0.0
    tilt_z: float = 0.0
    order: int = 0

    def rotation(self) -> np.ndarray:
        """The 3×3 matrix whose columns are the new axes in the old frame."""
        x, y, z = (_turn(axis, degrees) for axis, degrees in enumerate((self.tilt_x, self.tilt_y, self.tilt_z)))
        return x @ y @ z if self.order == 0 else z @ y @ x

    def apply(self, origin: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The frame (origin, axes: columns) after this break of the frame (`origin`, `axes`)."""
        shift = np.array([self.decentre_x, self.decentre_y, 0.0])
        if self.order == 0:
            return origin + axes @ shift, axes @ self.rotation()
        turned = axes @ self.rotation()
        return origin + turned @ shift, turned

    def scaled(self, factor: float) -> Placement:
        """The break of a lens grown by `factor`: its decentres times `factor`, its tilts kept."""
        return replace(self, decentre_x=self.decentre_x * factor, decentre_y=self.decentre_y * factor)

    def table(self) -> dict:
        """Its entries in a lens file's [[surface]] row: the values other than 0 (`KEYS`' names)."""
        return {key: value for key, value in zip(KEYS, astuple(self)) if value}


KEYS = tuple(f"tilt_{f.name}" if f.name == "order" else f.name for f in fields(Placement))
"""A [[surface]] row's entries of its placement, in `Placement`'s field order (`order` as `tilt_order`)."""


def from_row(row: dict, ident: str, number) -> Placement | None:
    """The break a lens file's row (a [[surface]] or the [image] table) gives by its `KEYS`, each checked by
    `number` (`surface.finite_number`); None without any; SolasError naming a bad one."""
    if not any(key in row for key in KEYS):
        return None
    order = row.get("tilt_order", 0)
    if not isinstance(order, int) or isinstance(order, bool) or order not in ORDERS:
        raise SolasError(
            f"{ident}: tilt_order = {order!r} must be one of {', '.join(map(str, ORDERS))} (0: decentre, then tilt "
            "about x, y, z; 1: tilt about z, y, x, then decentre; Zemax's order flag)"
        )
    values = {key: number(row, key, ident, "mm" if key.startswith("decentre") else "degrees", 0.0) for key in KEYS[:-1]}
    _check_tilts(values, ident)
    return Placement(**values, order=order)


def _check_tilts(values: dict, ident: str) -> None:
    """SolasError naming a tilt of `values` (a row's placement entries) outside `FACING_LIMIT` or `SPIN_LIMIT`."""
    for key in ("tilt_x", "tilt_y"):
        if not abs(values[key]) < FACING_LIMIT:
            raise SolasError(
                f"{ident}: {key} = {values[key]:g} degrees; |{key}| must be below {FACING_LIMIT:g} (at "
                f"{FACING_LIMIT:g} or more the surface turns edge-on or backward)"
            )
    if not abs(values["tilt_z"]) <= SPIN_LIMIT:
        raise SolasError(
            f"{ident}: tilt_z = {values['tilt_z']:g} degrees; |tilt_z| must be at most {SPIN_LIMIT:g} (a spin about "
            "the axis)"
        )


def _turn(axis: int, degrees: float) -> np.ndarray:
    """The right-hand rotation by `degrees` about coordinate `axis` (0 x, 1 y, 2 z)."""
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    i, j = [k for k in range(3) if k != axis]
    m = np.eye(3)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m if axis != 1 else m.T  # about y the right-hand rule turns z toward x


def frames(surfaces, image: Placement | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """(vertex, axes) of each of `surfaces` and then of the image plane, in surface 1's frame before any
    break: each surface's `placement` applied at the point its predecessor's thickness reaches, `image` (a
    lens's `image_placement`: the sensor decentred or tilted) at the point the last thickness reaches."""
    origin, axes, out = np.zeros(3), np.eye(3), []
    for s in surfaces:
        if s.placement is not None:
            origin, axes = s.placement.apply(origin, axes)
        out.append((origin, axes))
        origin = origin + axes[:, 2] * s.thickness
    out.append(image.apply(origin, axes) if image is not None else (origin, axes))
    return out


def moved(p: Placement | None) -> bool:
    """Whether break `p` decentres or tilts (a break of zeros, or none, leaves the frame where it is)."""
    return p is not None and any(astuple(p)[:-1])


def metadata(lens) -> dict:
    """{"paraxial_axis": a note that `lens`'s paraxial data are about its nominal axis}, where a coordinate break
    decentres or tilts a surface or the sensor (the paraxial trace ignores the breaks: an approximation of the
    lens as built); {} for a lens on one axis."""
    surfaces = [str(i) for i, s in enumerate(lens.surfaces, start=1) if moved(s.placement)]
    parts = [f"surface {', '.join(surfaces)} decentred or tilted"] * bool(surfaces)
    parts += ["the sensor decentred or tilted"] * moved(lens.image_placement)
    if not parts:
        return {}
    return {
        "paraxial_axis": "paraxial data (EFL, BFD, pupils, f-numbers, paraxial chief rays) are about the nominal axis "
        f"(surface 1's, before any coordinate break), which approximates the lens as built: {' and '.join(parts)}"
    }
