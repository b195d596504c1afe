"""Stiff and extreme cases of one lens, each with what must happen and what does: the answer is
accurate, or a warning or a clear refusal says it is not — never a silent wrong number, a NaN or a
crash (`solas-mi check-stability LENS`).

Each case derives its expectation from physics or from a refinement of the same computation:
pupil sampling against twice the samples, the window's energy against the transmitted power, wave
optics' transmission against ray optics', far objects against the object at infinity, a near-flat
surface against a flat one, rays through the centre of a monocentric shell undeviated, the
float64 OPD's symmetry on axis, and the render's exit-pupil bound against every ray that leaves the
lens. Fields are degrees, wavelengths nm, lengths mm.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import SolasError
from ..optics import tracer
from ..optics.exit_pupil import passes, pupil_bounds, reversed_lens
from ..optics.lens import Lens
from ..optics.paraxial import paraxial
from ..optics.pupil import Bundle, chief_rays, pupil_function, widest_field
from ..psf.base import DEFAULT_PITCH_UM, DEFAULT_SIZE, WINDOW_ENERGY_LIMIT
from ..psf.fraunhofer import sampling_warnings
from ..psf.geometric import geometric
from ..psf.methods import psf
from ..psf.registry import DEFAULT_PUPIL_SAMPLES, MAX_SAMPLING

SAMPLING_TOLERANCE = 0.02  # of the PSF's peak: default pupil sampling against twice the samples
FAR_TOLERANCE = 1e-3  # of the peak: an object beyond 1e9 mm against the object at infinity
FAR_DISTANCES_MM = (1e2, 1e3, 1e4, 1e6, 1e9, 1e10, 1e12)
CENTRE_SCAN = 20001  # meridional rays that confirm no ray of a field reaches the stop centre
NEAR_FLAT_REFERENCE_MM = 1e8  # radius whose chief rays give the first-order effect of a near-flat surface's curvature


@dataclass
class Case:
    """One case: what was done, what must hold, what was seen, and whether it held."""

    name: str
    expected: str
    observed: str
    passed: bool

    def to_dict(self) -> dict:
        return {"case": self.name, "expected": self.expected, "observed": self.observed,
                "verdict": "pass" if self.passed else "FAIL"}


def _peak_error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / b.max())


def _sampling(lens: Lens, field: tuple, wl: float) -> list[Case]:
    reference = psf(lens, field, wl, pupil_samples=256)
    default = psf(lens, field, wl)
    coarse = psf(lens, field, wl, pupil_samples=16)
    err, err16 = _peak_error(default.data, reference.data), _peak_error(coarse.data, reference.data)
    flagged = bool(default.meta["warnings"])
    return [
        Case(f"pupil sampling 128 at {field[1]:g} deg", f"within {SAMPLING_TOLERANCE:.0%} of peak of 256 samples, "
             "or a warning", f"{err:.2%}" + (" (warned)" if flagged else ""), err <= SAMPLING_TOLERANCE or flagged),
        Case(f"pupil sampling 16 at {field[1]:g} deg", "a warning when more than 5 % of peak off",
             f"{err16:.1%}, " + ("warned" if coarse.meta["warnings"] else "no warning"),
             err16 <= 0.05 or bool(coarse.meta["warnings"])),
    ]


def _window(lens: Lens, field: tuple, wl: float) -> list[Case]:
    small = psf(lens, field, wl, size=16)
    grown = psf(lens, field, wl, size=16, auto_window=True)
    e, e2 = small.meta["energy_in_grid"], grown.meta["energy_in_grid"]
    low = e < WINDOW_ENERGY_LIMIT
    return [
        Case(f"16 px window at {field[1]:g} deg", f"a warning below {WINDOW_ENERGY_LIMIT:.0%} of the light",
             f"{e:.1%} inside, " + ("warned" if small.meta["warnings"] else "no warning"),
             low == bool(small.meta["warnings"]) or not low),
        Case(f"auto window at {field[1]:g} deg", f"{WINDOW_ENERGY_LIMIT:.0%} to {1 / WINDOW_ENERGY_LIMIT:.0%} of the "
             "light inside, or an aliasing warning", f"{e2:.1%} in {grown.size} px"
             + (" (warned)" if grown.meta["warnings"] else ""),
             WINDOW_ENERGY_LIMIT <= e2 <= 1 / WINDOW_ENERGY_LIMIT or bool(grown.meta["warnings"])),
    ]


def _transmission(lens: Lens, fields: np.ndarray, wl: float) -> Case:
    pf = pupil_function(lens, fields, np.full(len(fields), wl), DEFAULT_PUPIL_SAMPLES)
    rays = geometric(lens, fields, np.full(len(fields), wl), 2.0, 32, rays=400)[2]
    rel = np.abs(pf.transmission / rays - 1.0)
    flagged = bool(sampling_warnings(pf, DEFAULT_PITCH_UM, DEFAULT_SIZE, fields, most=MAX_SAMPLING))
    seen = ", ".join(f"{f[1]:g}°: {w:.4f}/{r:.4f}" for f, w, r in zip(fields, pf.transmission, rays))
    return Case("wave vs ray transmission", "within 1 % at 0, 0.7 and 1.0 of the field (TIR, vignetting), or the "
                "pupil flagged", seen + (" (flagged)" if flagged else ""), bool(rel.max() < 0.01) or flagged)


def _centred(lens: Lens, field: tuple, wl: float) -> Case:
    p = psf(lens, field, wl, method="geometric", size=64, pitch_um=2.0)
    y, x = np.indices(p.data.shape)
    cx, cy = (float((p.data * a).sum()) for a in (x, y))
    off = math.hypot(cx - p.size // 2, cy - p.size // 2)
    return Case(f"PSF centred on the light at {field[1]:g} deg", "centroid within a quarter window of the centre",
                f"{off:.1f} px of {p.size // 2}", off < p.size / 4)


def _chief(lens: Lens, wl: float) -> Case:
    fields = np.stack([np.zeros(11), np.linspace(0.0, lens.field_deg, 11)], axis=-1)
    chief = chief_rays(lens, fields, np.full(11, wl))
    tr = Bundle(lens, fields, np.full(11, wl), 1).trace(tracer.F(chief.entrance[:, 0]), tracer.F(chief.entrance[:, 1]))
    sx, sy = tracer.to_numpy(tr.stop_x, tr.stop_y)
    miss = np.hypot(sx, sy)
    off = chief.off_centre
    seen = f"{miss[~off].max(initial=0.0):.1e} mm"
    reached = [f for f in fields[off] if _reaches_centre(lens, f, wl)]
    if off.any():  # a field no ray reaches the stop centre from: the nearest passing ray, said so
        seen += (f"; from {fields[off][0, 1]:g} deg no ray reaches the centre (nearest {miss[off].max():.2g} mm), "
                 f"{'but a scan finds one' if reached else f'a scan of {CENTRE_SCAN} meridional rays agrees'}")
    return Case("chief ray through the stop centre", "within 1e-9 mm at 11 fields to the full field, or no "
                "ray of the field reaches it", seen, bool(miss[~off].max(initial=0.0) < 1e-9) and not reached)


def _reaches_centre(lens: Lens, field: np.ndarray, wl: float) -> bool:
    """Whether some meridional ray of `field` (0, y) crosses the stop centre: its stop height changes sign
    between neighbours of a scan over every entrance point that can meet the lens (TIR and misses left out)."""
    span = -tracer.launch_plane_z(lens) if lens.at_infinity else 2.0 * max(s.semi_diameter for s in lens.surfaces)
    ey = np.linspace(-span, span, CENTRE_SCAN)
    tr = Bundle(lens, np.tile(field, (CENTRE_SCAN, 1)), np.full(CENTRE_SCAN, wl), 1).trace(tracer.F(0.0 * ey),
                                                                                        tracer.F(ey))
    ok, sy = tracer.to_numpy(tr.ok, tr.stop_y)
    both = ok[1:] & ok[:-1]
    return bool(np.any(both & (np.sign(sy[1:]) != np.sign(sy[:-1]))))


def _beyond(lens: Lens, wl: float) -> Case:
    far = min(88.0, max(3.0 * lens.field_deg, lens.field_deg + 10.0))
    try:
        p = psf(lens, (0.0, far), wl, size=32)
        ok = bool(np.isfinite(p.data).all() and abs(p.data.sum() - 1.0) < 1e-9)
        seen = "finite, normalised PSF" if ok else "NaN or unnormalised PSF"
    except SolasError as exc:
        ok, seen = f"({0:g}, {far:g})" in str(exc), f"refused: {str(exc).split(';')[0]}"
    return Case(f"field {far:g} deg, beyond the design", "a finite normalised PSF or a refusal naming the field",
                seen, ok)


def _distances(lens: Lens, field: tuple, wl: float) -> list[Case]:
    try:
        at_infinity = psf(replace(lens, object_distance=math.inf), field, wl, size=96)
    except SolasError as exc:  # a lens made for a near object (a collimator's focus) may pass no light from infinity
        at_infinity = exc
    ref_t = None
    cases = []
    for d in FAR_DISTANCES_MM:
        try:
            p = psf(replace(lens, object_distance=d), field, wl, size=96)
        except SolasError as exc:
            cases.append(Case(f"object at {d:g} mm", "finite or a clear refusal", f"refused: {exc}",
                              "object" in str(exc) or "field" in str(exc)))
            continue
        finite = bool(np.isfinite(p.data).all()) and math.isfinite(p.meta["transmission"])
        ref_t = p.meta["transmission"] if d == 1e6 else ref_t
        if d < 1e9:
            cases.append(Case(f"object at {d:g} mm", "finite PSF and transmission",
                              f"transmission {p.meta['transmission']:.4f}", finite))
            continue
        cases.append(_far(d, p, at_infinity, ref_t, finite))
    return cases


def _far(d: float, p, at_infinity, ref_t: float | None, finite: bool) -> Case:
    """An object `d` mm away (beyond 1e9) against the object at infinity (a PSF, or its refusal)."""
    if isinstance(at_infinity, SolasError):
        t = p.meta["transmission"]
        return Case(f"object at {d:g} mm", "refused, or no light, as the object at infinity",
                    f"transmission {t:.1e} where infinity is refused: {str(at_infinity)[:60]}", finite and t < 1e-5)
    dt = abs(p.meta["transmission"] / ref_t - 1.0) if ref_t else 0.0
    flagged = bool(p.meta["warnings"] or at_infinity.meta["warnings"])
    if at_infinity.data.max() > 0:
        err = _peak_error(p.data, at_infinity.data)
        seen = f"{err:.1e} of peak, {dt:.1e}"
    else:  # the light from infinity misses the window (a lens made for a near object): no peak to compare
        err = 0.0 if p.data.max() == 0 else math.inf
        seen = f"no light in the window from infinity{'' if err == 0 else ', some from here'}, {dt:.1e}"
    return Case(f"object at {d:g} mm", f"PSF of infinity within {FAR_TOLERANCE:g} of peak, transmission of 1e6 mm "
                "within 1e-5, or a warning", seen + (" (warned)" if flagged else ""),
                finite and ((err < FAR_TOLERANCE and dt < 1e-5) or flagged))


def _glass_limits(lens: Lens) -> list[Case]:
    glasses = {s.glass for s in lens.surfaces} | {lens.object_glass}
    lo = max(g.range_nm[0] for g in glasses)
    hi = min(g.range_nm[1] for g in glasses)
    if lo == 0.0 and math.isinf(hi):  # air and ideal lenses alone: no wavelength limit to try
        return [Case("glass limits", "none where no medium has a range", "every medium holds at every wavelength", True)]
    cases = []
    for w in (lo, hi):
        efl = paraxial(lens, w).efl_mm
        cases.append(Case(f"wavelength {w:g} nm (glass limit)", "finite paraxial data", f"EFL {efl:.4f} mm",
                          math.isfinite(efl)))
    try:
        paraxial(lens, hi + 1.0)
        seen, ok = "accepted", False
    except SolasError as exc:
        seen, ok = str(exc), "valid range" in str(exc)
    cases.append(Case(f"wavelength {hi + 1:g} nm (beyond)", "a refusal naming the glass range", seen, ok))
    return cases


def _near_flat(lens: Lens, wl: float) -> Case:
    real = [i for i, s in enumerate(lens.surfaces) if not s.ideal]
    if not real:
        return Case("near-flat surface", "none in a lens of ideal lenses alone", "no surface to bend", True)
    k = next((i for i in real if lens.surfaces[i].radius == 0.0), real[0])

    def bent(radius: float) -> Lens:
        return replace(lens, surfaces=tuple(replace(s, radius=radius) if i == k else s
                                            for i, s in enumerate(lens.surfaces)))

    fields = np.array([[0.0, 0.0], [0.0, lens.field_deg]])
    flat, near, curved = (chief_rays(bent(r), fields, np.full(2, wl)).image_xy for r in (0.0, 1e12, NEAR_FLAT_REFERENCE_MM))
    # the curvature's own effect, linear in 1/R: what a curvature 1e4 times larger moves, 1e-4 times
    # (a collimator's flat face 92 mm from the object moves the image 1.8e-9 mm at R = 1e12 mm, 1.8e-5 at 1e8)
    expected = (curved - flat) * (NEAR_FLAT_REFERENCE_MM / 1e12)
    diff = float(np.abs(near - flat - expected).max())
    return Case(f"surface {k + 1} near-flat (R = 1e12 mm) vs flat", "the same chief rays within 1e-9 mm, beyond "
                "the curvature's own first-order effect", f"{diff:.1e} mm (effect {np.abs(expected).max():.1e} mm)",
                diff < 1e-9)


def _concentric(lens: Lens, wl: float) -> Case:
    glass = next((s.material for s in lens.surfaces if s.glass.kind != "air"), "N-BK7")
    shell = Lens.from_dict({"surface": [
        {"radius": 20.0, "thickness": 5.0, "diameter": 30.0, "material": glass, "stop": True},
        {"radius": 15.0, "thickness": 40.0, "diameter": 20.0}]})
    theta = np.linspace(-0.3, 0.3, 31)  # rad: collimated rays, each through the common centre z = 20
    zero = tracer.F(np.zeros_like(theta))
    rays = tracer.launch(shell, zero, tracer.F(np.tan(theta)), zero,
                         tracer.F(-(20.0 - tracer.launch_plane_z(shell)) * np.sin(theta)))
    tr = tracer.trace(shell, rays, tracer.F(np.full(len(theta), wl * 1e-3)))
    dy, dz = tracer.to_numpy(tr.rays.dy, tr.rays.dz)
    dev = float(np.abs(np.arctan2(dy, dz) - theta).max())
    return Case("rays through a monocentric shell's centre", "undeviated within 1e-12 rad", f"{dev:.1e} rad",
                dev < 1e-12)


def _opd_precision(lens: Lens, wl: float) -> Case:
    pf = pupil_function(lens, [[0.0, 0.0]], [wl], 64)
    waves = pf.opd_mm[0] / (wl * 1e-6)
    inside = pf.coverage[0] == 1.0
    asym = float(np.abs(waves - waves.T)[inside].max())
    path = float(abs(pf.chief.opl[0]))
    ulp32 = float(np.spacing(np.float32(path))) / (wl * 1e-6)  # one float32 rounding of the path, in waves
    return Case("OPD in float64 (float32 rounds the path)", "on-axis asymmetry < 1e-6 waves",
                f"{asym:.1e} waves (one float32 rounding of the {path:.0f} mm path: {ulp32:.3f} waves)", asym < 1e-6)


def _exit_pupil(lens: Lens, wl: float) -> Case:
    from ..optics.camera import camera_for

    if lens.surfaces[-1].thickness == 0:  # the bound is sampled over the last vertex plane, through the film
        try:
            pupil_bounds(lens, 1.0, [wl], radii=2, directions=8)
            seen, ok = "no refusal", False
        except SolasError as exc:
            seen, ok = f"refused: {str(exc).split(' (')[0]}", "image plane lies on the last surface" in str(exc)
        return Case("render's exit-pupil bound", "a refusal naming the image on the last surface", seen, ok)
    if not lens.field_type.pinhole:  # the image circle
        r_max = float(np.hypot(*chief_rays(lens, [[0.0, lens.field_deg]], [wl]).image_xy[0]))
    else:
        camera = camera_for(lens)
        r_max = 0.5e-3 * camera.pitch_um * math.hypot(camera.width, camera.height)  # the film's corner
    bounds = pupil_bounds(lens, r_max, [wl], radii=32, directions=128)
    rev = reversed_lens(lens)
    last = lens.surfaces[-1]
    reach = 2.0 * (last.semi_diameter + r_max)
    g = np.linspace(-reach, reach, 121)
    gx, gy = (a.ravel() for a in np.meshgrid(g, g))
    outside = total = 0
    for r in np.linspace(0.0, r_max, 9):
        ok = passes(rev, np.full(len(gx), r), 0.0, gx, gy, wl)
        u0, u1, v0, v1, _ = bounds.at(np.array(r))
        out = ok & ((gx < u0) | (gx > u1) | (gy < v0) | (gy > v1))
        outside, total = outside + int(out.sum()), total + int(ok.sum())
    return Case("render's exit-pupil bound", "holds every ray that leaves the lens (9 film radii)",
                f"{outside} of {total} rays outside", outside == 0 and total > 0)


def imaged_field(lens: Lens, wl: float) -> tuple[float, str]:
    """A field (degrees) for a lens whose file states none, and how it was found: the widest field whose
    chief ray passes its apertures (`pupil.widest_field`; a fisheye's table stops it short), or, where they
    pass the chief ray of every field the field type allows (a cemented achromat's to 88.5 deg, where no
    image forms), the paraxial field whose image height is the lens's largest clear semi-diameter (a lens's
    image is about as large as the lens: 7.2 deg for an f = 100 mm achromat 25.4 mm across)."""
    widest = widest_field(lens, wl)
    if widest < lens.field_type.largest_deg:
        return widest, "the widest field whose chief ray passes the apertures"
    size = max(s.semi_diameter for s in lens.surfaces)
    efl = abs(paraxial(lens, wl).efl_mm)
    field = min(widest, math.degrees(math.atan(size / efl)))
    return field, (f"the paraxial field of image height {size:g} mm, the largest clear semi-diameter, at EFL "
                   f"{efl:.4g} mm (the apertures pass every field to {widest:g} deg)")


def check_stability(lens: Lens, progress=None) -> list[Case]:
    """Every case for `lens` at its primary wavelength (see the module docstring); `progress(name)` is
    called before each group. An unexpected exception is a failed case, not a crash. A lens whose file
    states no field (a pbrt table, a Zemax file without fields) is checked at a field it images
    (`imaged_field`)."""
    wl = lens.primary_wavelength
    cases = []
    if lens.field_deg == 0:
        field, how = imaged_field(lens, wl)
        lens = replace(lens, field_deg=field)
        cases.append(Case("field of a lens that states none", "the widest field its apertures pass, or where they "
                          "pass every field, the paraxial field as large as the lens", f"{field:.3f} deg: {how}",
                          field > 0))
    full = (0.0, lens.field_deg)
    fields = np.array([[0.0, 0.0], [0.0, 0.7 * lens.field_deg], [0.0, lens.field_deg]])
    groups = [
        ("pupil sampling", lambda: _sampling(lens, full, wl)),
        ("window energy", lambda: _window(lens, full, wl)),
        ("transmission", lambda: [_transmission(lens, fields, wl)]),
        ("centring", lambda: [_centred(lens, full, wl)]),
        ("chief rays", lambda: [_chief(lens, wl), _beyond(lens, wl)]),
        ("object distance", lambda: _distances(lens, (0.0, 0.7 * lens.field_deg), wl)),
        ("glass limits", lambda: _glass_limits(lens)),
        ("surfaces", lambda: [_near_flat(lens, wl), _concentric(lens, wl)]),
        ("OPD precision", lambda: [_opd_precision(lens, wl)]),
        ("exit pupil", lambda: [_exit_pupil(lens, wl)]),
    ]
    for name, run in groups:
        if progress is not None:
            progress(name)
        try:
            cases.extend(run())
        except Exception as exc:  # a crash is what this command exists to find: report it as a failure
            cases.append(Case(name, "no exception", f"{type(exc).__name__}: {exc}"[:110], False))
    return cases


def markdown(lens: Lens, cases: list[Case]) -> str:
    """The table of `cases` as Markdown, with the count of passes."""
    rows = [f"check-stability {lens.name}: {sum(c.passed for c in cases)} of {len(cases)} cases pass", "",
            "| case | expected | observed | verdict |", "|---|---|---|---|"]
    rows += [f"| {c.name} | {c.expected} | {c.observed} | {'pass' if c.passed else '**FAIL**'} |" for c in cases]
    return "\n".join(rows)
