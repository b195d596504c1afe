"""The lens analyses against optiland, an independent lens design code, on every shipped lens.

optiland runs in a side virtual environment (never a dependency of solas-mi); this script exports each
lens at its primary wavelength (radii, thicknesses, the index after each surface, clear apertures, the
stop, the entrance-pupil diameter), runs benchmarks/optiland_reference.py with optiland's Python,
computes the same numbers with solas_mi.analysis, and prints per lens and analysis the largest
difference against its tolerance.

    python3 -m venv .optiland-venv && .optiland-venv/bin/pip install optiland
    .venv/bin/python benchmarks/bench_optiland.py [--optiland-python .optiland-venv/bin/python] [LENS ...]
    .venv/bin/python benchmarks/run_all.py bench_optiland        # records benchmarks/results/bench_optiland.md

Fields: 0, 0.5, 0.7 and 1 of the half field (below 90 deg: optiland's angle fields are tangents), on y;
curves against field at 11 fields from 0. Both aim real rays at points of the stop.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
FIELD_FRACTIONS = (0.0, 0.5, 0.7, 1.0)
CURVE_FIELDS = 11
FAN = np.linspace(-1.0, 1.0, 11)
MTF_FREQUENCIES = 40  # from 0 to half the cut-off
HUYGENS_SAMPLES = (128, 192, 256, 384, 512, 768)  # pupil samples a side the Huygens sum may take
HUYGENS_MARGIN = 0.25  # of the spot's diameter: its window's margin beyond the spot on either side
HUYGENS_TERMS = 5e10  # the most wavelet terms it may sum (about 1e8 a second on 2 loaded cores: 8 min)
GEOMETRIC_BAND = 0.03  # of the cut-off: where many waves of aberration leave diffraction little to change
TOLERANCES = {  # the issue's: MTF 0.01, focus 1 um, distortion 1e-4 %, Zernike 1e-3 waves; rays 1 nm
    "chief ray height (mm)": 1e-6,
    "ray fan (um)": 1e-3,
    "field curvature (mm)": 1e-3,
    "distortion f-tan (%)": 1e-4,
    "distortion f-theta (%)": 1e-4,
    "lateral colour (um)": 1e-3,
    "OPD fan (waves)": 1e-3,
    "Zernike fringe 1-36 (waves)": 1e-3,
    "MTF": 0.01,
    "Zernike: sphere convention (waves)": np.inf,  # ours about our own sphere: what the convention alone makes
}


def largest_field(lens) -> float:
    """The lens's half field, kept below 90 deg (optiland's angle fields are tangents)."""
    return min(lens.field_deg, 89.0)


def request(lens) -> dict:
    """What optiland_reference.py needs of one lens at its primary wavelength."""
    from solas_mi.optics.paraxial import paraxial

    wl = lens.primary_wavelength
    n = lens.indices(wl)
    top = largest_field(lens)
    return {
        "surfaces": [
            {
                "radius": s.radius,
                "thickness": s.thickness,
                "index_after": float(n[i + 1]),
                "semi_diameter": s.semi_diameter,
                "stop": s.stop,
                "conic": s.conic,
                "aspheric": list(s.aspheric),  # A4, A6, ...: a drawn lens's irregularity (`optics.tolerance`); no Qbfs
            }
            for i, s in enumerate(lens.surfaces)
        ],
        "epd_mm": paraxial(lens, wl).entrance_pupil_diameter_mm,
        "wavelength_nm": wl,
        "max_field_deg": top,
        "fields_deg": [f * top for f in FIELD_FRACTIONS],
        "curve_fields_deg": np.linspace(0, top, CURVE_FIELDS).tolist(),
        "colour": [
            {"wavelength_nm": w, "index_after": lens.indices(w)[1:].tolist()} for w in (*lens.wavelengths_nm, wl)
        ],
        "fan_pupil": FAN.tolist(),
        "zernike_rings": 32,
        "opd_fan_rays": len(FAN),
        "mtf_rays": 256,
        "mtf_grid": 512,
    }


def run_optiland(python: str, requests: dict) -> dict:
    """optiland_reference.py's results for `requests` (name → `request`)."""
    with tempfile.TemporaryDirectory() as tmp:
        source, target = Path(tmp) / "request.json", Path(tmp) / "result.json"
        source.write_text(json.dumps({"lenses": requests}))
        subprocess.run(
            [python, str(HERE / "optiland_reference.py"), str(source), str(target)],
            check=True,
            env={**os.environ, "PYTHONWARNINGS": "ignore"},
            stderr=subprocess.DEVNULL,
        )
        return json.loads(target.read_text())


def ours(lens, spec: dict) -> dict:
    """solas-mi's numbers for what `spec` asks (`request`)."""
    from solas_mi.analysis.colour import lateral_colour
    from solas_mi.analysis.distortion import distortion
    from solas_mi.analysis.field_curvature import field_curvature
    from solas_mi.analysis.mtf import lens_otf
    from solas_mi.analysis.rays import pupil_rays
    from solas_mi.optics.pupil import chief_rays

    wl, fields = spec["wavelength_nm"], spec["fields_deg"]
    chief = chief_rays(lens, np.array([[0.0, f] for f in fields]), np.full(len(fields), wl)).image_xy[:, 1]
    zero = np.zeros_like(FAN)
    rays = pupil_rays(
        lens,
        fields,
        np.full(len(fields), wl),
        np.concatenate([zero, FAN]),
        np.concatenate([FAN, zero]),
        axial_sphere(lens, spec),
    )
    n = len(FAN)
    y = np.where(rays.ok, rays.y_mm, np.nan)[:, :n] - chief[:, None]
    x = np.where(rays.ok, rays.x_mm, np.nan)[:, n:]
    within = replace(lens, field_deg=spec["max_field_deg"])  # the fisheye's 90 deg: 89 (`largest_field`)
    d = distortion(within, field_samples=CURVE_FIELDS, wavelength_nm=wl)
    c = field_curvature(within, field_samples=CURVE_FIELDS, wavelengths_nm=[wl])
    colour = lateral_colour(within, field_samples=CURVE_FIELDS, wavelengths_nm=lens.wavelengths_nm)
    return {
        "chief": chief,
        "fan_y": y,
        "fan_x": x,
        "opd_y": rays.wavefront_waves[:, :n],
        "opd_x": rays.wavefront_waves[:, n:],
        "distortion": d,
        "curvature": c,
        "colour": colour.values,
        "otf": lambda freq: np.abs(lens_otf(lens, fields, (wl,), (1.0,), freq, None)[0]),
    }


def axial_sphere(lens, spec: dict) -> np.ndarray:
    """Per field, the radius (mm) of optiland's reference sphere: from the chief ray's image point to the
    paraxial exit pupil's centre on the axis. solas-mi's (as Zemax's) reaches the chief ray's crossing of the
    exit-pupil plane instead; the wavefronts differ by the defocus between the two spheres (the Double Gauss
    at 22 deg: 3e-3 waves), a convention, which the comparison takes optiland's for."""
    from solas_mi.optics.paraxial import paraxial
    from solas_mi.optics.pupil import chief_rays

    wl, fields = spec["wavelength_nm"], spec["fields_deg"]
    y = chief_rays(lens, np.array([[0.0, f] for f in fields]), np.full(len(fields), wl)).image_xy[:, 1]
    return np.hypot(y, lens.image_z - paraxial(lens, wl).exit_pupil_z_mm)


def zernike_at(lens, spec: dict, points, radius: np.ndarray | None) -> np.ndarray:
    """Our Fringe terms 1-36 (waves) per field, fitted (`analysis.zernike.fit`) to our wavefront (about the
    reference sphere of `radius` per field; None: ours) at optiland's own sample points (its hexapolar
    pattern, where its rays arrive): over a vignetted pupil a least-squares fit depends on where it is
    sampled (the Double Gauss at full field: 0.25 waves between a square grid and optiland's rings), so
    both fit the same points."""
    from solas_mi.analysis.rays import pupil_rays
    from solas_mi.analysis.zernike import fit

    out = []
    for i, (f, (x, y, *_)) in enumerate(zip(spec["fields_deg"], points)):
        x, y = np.array(x), np.array(y)
        rays = pupil_rays(lens, [f], [spec["wavelength_nm"]], x, y, None if radius is None else radius[i : i + 1])
        ok = rays.ok[0]
        out.append(fit("fringe", 36, x[ok], y[ok], rays.wavefront_waves[0][ok]))
    return np.array(out)


def gap(mine, theirs) -> float | None:
    """The largest |mine − theirs| where both are numbers (a blocked ray is NaN in both); None where
    optiland gives no finite number at all (its f-tan reference on the fisheye is infinite)."""
    mine, theirs = np.asarray(mine, dtype=float), np.asarray(theirs, dtype=float)
    both = np.isfinite(mine) & np.isfinite(theirs)
    return float(np.abs(mine - theirs)[both].max()) if both.any() else None


def differences(lens, spec: dict, theirs: dict) -> dict[str, float | None]:
    """Analysis → the largest |ours − optiland's| over fields, pupil points, frequencies, terms."""
    mine = ours(lens, spec)
    chief = np.array(theirs["chief_y_mm"])
    points = theirs["zernike_points"]
    out = {
        "chief ray height (mm)": gap(mine["chief"], chief),
        "ray fan (um)": gap(
            1e3 * np.concatenate([mine["fan_y"], mine["fan_x"]]),
            1e3 * np.concatenate([np.array(theirs["fan_y_mm"]) - chief[:, None], theirs["fan_x_mm"]]),
        ),
        "OPD fan (waves)": gap(
            np.concatenate([mine["opd_y"], mine["opd_x"]]), np.concatenate([theirs["opd_fan_y"], theirs["opd_fan_x"]])
        ),
        "Zernike fringe 1-36 (waves)": gap(zernike_at(lens, spec, points, axial_sphere(lens, spec)), theirs["zernike"]),
        "Zernike: sphere convention (waves)": gap(zernike_at(lens, spec, points, None), theirs["zernike"]),
        "distortion f-tan (%)": gap(mine["distortion"].f_tan_percent[1:], theirs["f-tan"][1:]),  # 0 on the axis
        "distortion f-theta (%)": gap(mine["distortion"].f_theta_percent[1:], theirs["f-theta"][1:]),
        "lateral colour (um)": gap(
            mine["colour"], 1e3 * (np.array(theirs["colour_chief_y_mm"][:-1]) - theirs["colour_chief_y_mm"][-1])
        ),
        "field curvature (mm)": gap(
            np.concatenate([mine["curvature"].tangential_mm[0], mine["curvature"].sagittal_mm[0]]),
            np.concatenate([theirs["tangential_mm"], theirs["sagittal_mm"]]),
        ),
    }
    freq, ours_mtf, their_mtf = mtf_curves(lens, spec, mine["otf"], theirs)
    out["MTF"] = gap(ours_mtf, their_mtf)
    out["third route"] = third_route(lens, spec, freq, ours_mtf, their_mtf)
    return out


def mtf_curves(lens, spec: dict, otf, theirs: dict):
    """Frequencies (0 to half the cut-off) and the MTF (fields, 2, F), [tangential, sagittal], of ours and
    of optiland (its curves interpolated)."""
    from solas_mi.analysis.inputs import cutoff_cy_mm

    freq = np.linspace(0.0, 0.5 * cutoff_cy_mm(lens, spec["wavelength_nm"]), MTF_FREQUENCIES)
    other = np.array(
        [
            [np.interp(freq, theirs[f"freq_{key}"][i], theirs[key][i]) for key in ("tangential", "sagittal")]
            for i in range(len(spec["fields_deg"]))
        ]
    )
    return freq, otf(freq), other


def huygens_window(lens, field: float, wavelength_nm: float) -> tuple[float, np.ndarray, np.ndarray]:
    """The Huygens PSF's pitch (µm, lambda N / 2: the PSF holds no frequency above 1/(lambda N)) and its
    pixels' offsets (mm) from the chief ray's image point along x (from 0: the PSF of a field on y is even
    in x) and y: each axis spans the ray spot's extent widened on either side by HUYGENS_MARGIN of its
    diameter and 4 lambda N."""
    from solas_mi.optics.paraxial import paraxial
    from solas_mi.optics.spot import spot

    pitch = 0.5 * wavelength_nm * 1e-3 * paraxial(lens, wavelength_nm).working_f_number
    s = spot(lens, (0.0, field), wavelength_nm)
    margin = HUYGENS_MARGIN * 2 * np.hypot(s.x_um, s.y_um).max() + 8 * pitch
    x = np.arange(0, (np.abs(s.x_um).max() + margin) / pitch + 1)
    y = np.arange(np.floor((s.y_um.min() - margin) / pitch), np.ceil((s.y_um.max() + margin) / pitch) + 1)
    return pitch, x * pitch * 1e-3, y * pitch * 1e-3


def huygens_mtf(lens, field: float, pf, direction: int, freq: np.ndarray) -> tuple[np.ndarray, float, float]:
    """The third route: the MTF along y (direction 0) or x (1) as the Fourier transform of a PSF summed
    wavelet by wavelet over the exit pupil's reference sphere (Rayleigh-Sommerfeld: U(P) = (1/(i lambda))
    sum a(Q) e^{ik(W + |P - Q|)} / |P - Q| dS, exact distances to each image point, no Fraunhofer
    approximation; `huygens.huygens_intensity`), a(Q) the field amplitude on the sphere (power per area:
    power per d alpha d beta times gamma / R^2, dS = R^2 d alpha d beta / gamma) of the pupil function `pf`
    (of the field `field` on y, one wavelength), over the total (the light beyond the window is in it: the curve is
    meaningful from a few cycles per window on); with the lowest such frequency and the share of the light
    the window holds. Window: `huygens_window`."""
    from huygens import huygens_intensity

    wavelength_nm = pf.wavelength_nm[0]
    pitch, x, y = huygens_window(lens, field, wavelength_nm)
    a, b = np.meshgrid(pf.alpha[0] + pf.chief.sphere_point[0, 0], pf.beta[0] + pf.chief.sphere_point[0, 1])
    inside = pf.amplitude[0] > 0
    gamma = np.sqrt(1 - a[inside] ** 2 - b[inside] ** 2)
    radius, lam = pf.chief.sphere_radius[0], wavelength_nm * 1e-6
    area = radius**2 * pf.cell_area[0] / gamma
    k = 2 * np.pi / lam
    weight = pf.amplitude[0][inside] * np.sqrt(gamma) / radius * np.exp(1j * k * pf.opd_mm[0][inside]) * area / lam
    half = huygens_intensity(a[inside], b[inside], weight, radius, lam, x, y) * (pitch * 1e-3) ** 2  # per pixel
    intensity = np.concatenate([half[:, :0:-1], half], axis=1)  # rows: y; columns: x from -x[-1] to x[-1]
    x = np.concatenate([-x[:0:-1], x])
    lsf, at = (intensity.sum(axis=1), y) if direction == 0 else (intensity.sum(axis=0), x)
    # the total in the same measure: Parseval on the image plane, where an oblique pencil's |U|^2 is its
    # power per area over gamma (the chief ray 12 deg off the axis: 2.3 %)
    total = np.sum(pf.amplitude[0][inside] ** 2 * pf.cell_area[0] / gamma)
    mtf = np.abs(np.exp(-2j * np.pi * np.outer(freq, at)) @ lsf) / total
    return mtf, 5.0 / (at[-1] - at[0]), float(intensity.sum() / total)


def huygens_pupil(lens, field: float, wavelength_nm: float):
    """The pupil function of the fewest of HUYGENS_SAMPLES pupil samples that resolve the wavefront (phase
    steps within pi per cell) and with which the Huygens sum is affordable (`huygens_affordable`), None if
    none does."""
    from solas_mi.optics.pupil import pupil_functions
    from solas_mi.psf.fraunhofer import sampling_need

    for pf in pupil_functions(lens, np.array([[0.0, field]]), np.array([wavelength_nm]), HUYGENS_SAMPLES):
        if sampling_need(pf, 1.0, 1)[0][0] <= np.pi and huygens_affordable(lens, field, pf):
            return pf
    return None


def huygens_affordable(lens, field: float, pf) -> bool:
    """Whether `huygens_mtf` with the pupil function `pf` takes at most HUYGENS_TERMS wavelet terms (pupil
    samples times image points) and its window lies within the period lambda / d alpha of the PSF that
    the pupil's sampling makes (a coarser grid folds the spot onto itself)."""
    _, x, y = huygens_window(lens, field, pf.wavelength_nm[0])
    period = pf.wavelength_nm[0] * 1e-6 / np.array([np.diff(pf.alpha[0, :2])[0], np.diff(pf.beta[0, :2])[0]])
    terms = np.count_nonzero(pf.amplitude[0] > 0) * len(x) * len(y)
    return bool(terms <= HUYGENS_TERMS and 2 * x[-1] < period[0] and y[-1] - y[0] < period[1])


def third_route(lens, spec: dict, freq, mine, other) -> list[str]:
    """Where ours and optiland's MTF differ by more than the tolerance: at the worst field and direction,
    each against a third route, as a table row: the Huygens-Fresnel sum (`huygens_mtf`) where up to 768
    pupil samples a side resolve the wavefront and make it affordable (`huygens_pupil`); else (tens
    of waves of aberration: the Huygens sum would need thousands of samples a side) the geometric MTF (the
    Fourier transform of the ray spot, rays on an entrance grid, no pupil function), the limit the MTF tends to
    where the wavefront error is many waves, to GEOMETRIC_BAND of the cut-off (an approximation: it
    decides a large gap, not one of 0.01)."""
    from solas_mi.analysis.inputs import cutoff_cy_mm
    from solas_mi.analysis.mtf import geometric_otf

    gap = np.abs(mine - other).max(axis=2)
    i, d = np.unravel_index(int(np.argmax(gap)), gap.shape)
    if gap[i, d] <= TOLERANCES["MTF"]:
        return []
    field, wl = spec["fields_deg"][i], spec["wavelength_nm"]
    pf = huygens_pupil(lens, field, wl)
    if pf is not None:
        third, lowest, held = huygens_mtf(lens, field, pf, d, freq)
        band = freq >= lowest
        route = f"Huygens ({pf.alpha.shape[1]}² samples, {held:.4f} of the light) from {lowest:.3g} cy/mm"
    else:
        third = np.abs(geometric_otf(lens, (field,), (wl,), (1.0,), freq, 512)[0, d])
        top = GEOMETRIC_BAND * cutoff_cy_mm(lens, wl)
        band, route = freq <= top, f"geometric to {top:.3g} cy/mm"
    return [
        f"| {lens.name} | {field:.4g} | {('tangential', 'sagittal')[d]} | {gap[i, d]:.3f} | {route} | "
        f"{np.abs(mine[i, d] - third)[band].max():.4f} | {np.abs(other[i, d] - third)[band].max():.4f} |"
    ]


def main(argv: list[str] | None = None) -> int:
    from solas_mi import Lens
    from solas_mi.optics.formats import shipped_lenses

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("lenses", nargs="*", help="shipped lens names (default: every one)")
    ap.add_argument(
        "--optiland-python",
        default=os.environ.get("OPTILAND_PYTHON", ".optiland-venv/bin/python"),
        help="the Python of optiland's environment (default: $OPTILAND_PYTHON or .optiland-venv/bin/python)",
    )
    args = ap.parse_args(argv)
    if not Path(args.optiland_python).is_file():
        ap.error(f"no optiland environment at {args.optiland_python}: make one (see the top of this file)")
    lenses = {name: Lens.load(name) for name in (args.lenses or shipped_lenses())}
    theirs = run_optiland(args.optiland_python, {name: request(lens) for name, lens in lenses.items()})
    print(
        f"optiland {theirs['optiland']} (NumPy {theirs['numpy']}) against solas-mi, each lens at its primary "
        "wavelength; the largest difference over fields (0, 0.5, 0.7, 1 of the half field), pupil points, frequencies "
        "(to half the cut-off) and terms, tolerance in brackets:"
    )
    print()
    print("| lens | " + " | ".join(f"{k} [{v:g}]" if np.isfinite(v) else k for k, v in TOLERANCES.items()) + " |")
    print("|---|" + "---|" * len(TOLERANCES))
    third, errors = [], []
    for name, lens in lenses.items():
        found = differences(lens, request(lens), theirs["lenses"][name])
        cells = [
            (
                "n/a (optiland: not finite)"
                if found[k] is None
                else f"{found[k]:.2g}" + ("" if found[k] <= v else " **over**")
            )
            for k, v in TOLERANCES.items()
        ]
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
        third += found["third route"]
        errors += [f"optiland failed on {name}: {e}" for e in theirs["lenses"][name].get("errors", [])]
    if third:
        print(
            "\nWhere the MTFs differ beyond 0.01, the worst field and direction against a third route: a Huygens-Fresnel "
            f"sum over the exit pupil's reference sphere where up to {HUYGENS_SAMPLES[-1]} pupil samples a side resolve the "
            f"wavefront and it takes at most {HUYGENS_TERMS:.2g} wavelet terms, else the geometric MTF of the ray spot (the limit of many waves of aberration, "
            "an approximation); the largest difference in its band:\n"
        )
        print("| lens | field (deg) | direction | ours vs optiland | third route | ours vs third | optiland vs third |")
        print("|---|---|---|---|---|---|---|")
        print("\n".join(third))
    for line in errors:
        print(f"\n{line}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
