"""Overlapping surfaces (`Lens.overlaps`): neighbouring faces that cross inside their clear apertures (a
negative thickness, glass or air, an air gap closing before the rim) and an image plane on the last surface.
Zemax and optiland trace such a lens sequentially, each ray from one surface to the next along its line, a
signed step that may be negative; so does the tracer (`tracer._to_surface`). No solid geometry holds it, so
the mesh scene refuses it (`render.scene`). Glass of thickness 0 whose faces only touch is refused: no glass
lies between its faces and nothing overlaps, most likely a thickness left out.
"""

from __future__ import annotations

import numpy as np

from ..errors import SolasError
from . import glass as glass_mod

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
    for i, (a, b) in enumerate(zip(lens.surfaces[:-1], lens.surfaces[1:]), start=1):
        if (plane[i - 1] or plane[i]) and a.thickness >= 0:
            continue
        glass = a.glass is not glass_mod.AIR
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


def check_image_distance(lens, what: str) -> None:
    """SolasError where `lens`'s image plane lies on its last surface: `what` samples the rays from an image
    point over the last vertex plane, which then passes through the point, so that nothing is defined there."""
    if lens.surfaces[-1].thickness == 0:
        raise SolasError(
            f"lens {lens.name}: the image plane lies on the last surface (distance 0 mm), where {what}, "
            "sampled over the last vertex plane seen from the image point, is undefined; a PSF method "
            "that traces the lens (`psf --psf-method`) takes it as it is"
        )
