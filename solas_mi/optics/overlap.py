"""Overlapping surfaces (`Lens.overlaps`): neighbouring faces that cross inside their clear apertures (a
negative thickness, glass or air, an air gap closing before the rim) and an image plane on the last surface; for
a face that a coordinate break decentres or tilts, or without rotational symmetry, over the whole clear aperture
in each face's frame (the lens as built).
Zemax and optiland trace such a lens sequentially, each ray from one surface to the next along its line, a
signed step that may be negative; so does the tracer (`tracer._to_surface`). No solid geometry holds it, so
the mesh scene refuses it (`render.scene`). Glass of thickness 0 whose faces only touch is refused: no glass
lies between its faces and nothing overlaps, most likely a thickness left out.
"""

from __future__ import annotations

import numpy as np

from ..errors import SolasError
from . import glass as glass_mod
from .placement import frames, moved

SEQUENTIAL = "traced sequentially, as Zemax does; the lens cannot be built as solid geometry"


def metadata(lens) -> dict:
    """{"overlaps": `lens`'s overlaps in words (`Lens.overlaps`)} for PSF metadata and `lens info`; {} when
    none overlap."""
    return {"overlaps": list(lens.overlaps)} if lens.overlaps else {}


def notes(lens, where: str) -> list[str]:
    """`Lens.overlaps` of `lens`, in words (`where` names the lens); SolasError for glass of thickness 0
    whose faces only touch (a missing thickness: no glass between its faces, nothing overlapping)."""
    notes = []
    # A flat stop in air refracts nothing: the sequential trace checks each ray where its line crosses the
    # plane, even inside a neighbouring face's sag (Zemax's stop "on" a lens surface), as OpticStudio does.
    media = (lens.object_glass, *(s.glass for s in lens.surfaces))
    plane = [
        s.stop and s.radius == 0 and not (s.aspheric or s.qbfs) and s.glass is m is glass_mod.AIR
        for s, m in zip(lens.surfaces, media)
    ]
    placed = frames(lens.surfaces)
    for i, (a, b) in enumerate(zip(lens.surfaces[:-1], lens.surfaces[1:]), start=1):
        if (plane[i - 1] or plane[i]) and a.thickness >= 0:
            continue
        glass = a.glass is not glass_mod.AIR
        if moved(b.placement) or a.form is not None or b.form is not None:
            note = _between_placed(a, b, placed[i - 1], placed[i])
        else:
            note = _between(a, b, glass)
        if glass and a.thickness == 0 and note is None:
            raise SolasError(
                f"{where}: surface {i} ({a.label}): thickness 0 mm inside glass {a.material}, its "
                f"faces touching without crossing; glass needs a positive thickness (faces that "
                "overlap, a negative thickness, are traced as Zemax does)"
            )
        if note:
            notes.append(f"surfaces {i} ({a.label}) and {i + 1} ({b.label}) {note}: {SEQUENTIAL}")
    if lens.surfaces[-1].thickness == 0:
        notes.append(
            f"the image plane lies on surface {len(lens.surfaces)} ({lens.surfaces[-1].label}) "
            f"(distance 0 mm): {SEQUENTIAL}"
        )
    return notes


def _between(a, b, glass: bool) -> str | None:
    """Where surface `b`'s face comes before surface `a`'s (their gap negative) inside the smaller clear
    aperture, in words ("overlap within r = 0.023 mm …", "cross at r = 59.05 mm …"); for glass (`glass`),
    also where the faces meet at an edge of zero thickness; None where they do neither."""
    rim = min(a.semi_diameter, b.semi_diameter)
    gap = lambda r: a.thickness + b.sag(r) - a.sag(r)  # noqa: E731
    r = np.linspace(0.0, rim, 257)
    g = gap(r)
    tol = 1e-12 * max(1.0, abs(a.thickness))
    if not np.any(g < -tol):
        meet = np.flatnonzero(g[1:] <= tol) + 1 if glass and a.thickness > 0 else []
        return (
            (
                f"meet at r = {r[meet[0]]:.4g} mm inside their clear apertures (glass of zero edge thickness, "
                f"thickness {a.thickness:g} mm)"
            )
            if len(meet)
            else None
        )
    neg = g < -tol
    change = np.flatnonzero(np.diff(neg))
    if len(change) == 0:
        return f"overlap across their clear apertures (to r = {rim:.4g} mm; thickness {a.thickness:g} mm)"
    lo, hi = r[change[0]], r[change[0] + 1]
    for _ in range(60):  # the first edge of the overlap, to a few ulps
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if (gap(mid) < -tol) == neg[0] else (lo, mid)
    where = "overlap within" if neg[0] else "cross at"
    return f"{where} r = {lo:.4g} mm inside their clear apertures (thickness {a.thickness:g} mm)"


def _between_placed(a, b, frame_a, frame_b) -> str | None:
    """Where surface `b`'s face comes before surface `a`'s inside both clear apertures, for a pair that a coordinate
    break before `b` decentres or tilts, or a face without rotational symmetry: points of `b`'s face over its clear
    aperture (`PLACED_RINGS` rings of `PLACED_ANGLES` points) moved into `a`'s frame (`frame_a`, `frame_b`: their
    (origin, axes), `placement.frames`) against `a`'s sag there; in words, or None where none comes first."""
    r = np.linspace(0.0, b.semi_diameter, PLACED_RINGS)[:, None]
    angle = np.linspace(0.0, 2.0 * np.pi, PLACED_ANGLES, endpoint=False)[None, :]
    x, y = (r * np.cos(angle)).ravel(), (r * np.sin(angle)).ravel()
    points = frame_b[0] + np.stack([x, y, b.geometry.sag(x, y)], axis=1) @ frame_b[1].T
    q = (points - frame_a[0]) @ frame_a[1]
    with np.errstate(invalid="ignore"):
        gap = q[:, 2] - a.geometry.sag(q[:, 0], q[:, 1])
        first = (np.hypot(q[:, 0], q[:, 1]) <= a.semi_diameter) & (gap < -1e-12 * max(1.0, abs(a.thickness)))
    if not first.any():
        return None
    k = np.flatnonzero(first)[0]  # the innermost ring's first point
    return (
        f"overlap at (x, y) = ({q[k, 0]:.4g}, {q[k, 1]:.4g}) mm of the first's frame inside their clear apertures, "
        f"decentred, tilted or without rotational symmetry (thickness {a.thickness:g} mm)"
    )


PLACED_RINGS = 65  # rings of `_between_placed`'s points over a face's clear aperture, the axis included
PLACED_ANGLES = 64  # points on each ring


def check_image_distance(lens, what: str) -> None:
    """SolasError where `lens`'s image plane lies on its last surface: `what` samples the rays from an image
    point over the last vertex plane, which then passes through the point, so that nothing is defined there."""
    if lens.surfaces[-1].thickness == 0:
        raise SolasError(
            f"lens {lens.name}: the image plane lies on the last surface (distance 0 mm), where {what}, "
            "sampled over the last vertex plane seen from the image point, is undefined; a PSF method "
            "that traces the lens (`psf --psf-method`) takes it as it is"
        )
