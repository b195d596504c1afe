"""The lens analyses of optiland, an independent open-source lens design code, on prescriptions that
benchmarks/bench_optiland.py exports: run with optiland's own Python (a side virtual environment, never
a dependency of solas-mi), reads REQUEST.json, writes RESULT.json. It does not import solas-mi.

    python3 -m venv .optiland-venv && .optiland-venv/bin/pip install optiland
    .optiland-venv/bin/python benchmarks/optiland_reference.py REQUEST.json RESULT.json

Each lens comes as its surfaces at one wavelength: radius (0: flat), thickness, the index after the
surface, clear semi-diameter, the stop; the entrance-pupil diameter; an object at infinity. optiland
builds it with constant-index media (`IdealMaterial`, the index of that wavelength), a radial aperture
on every surface (so rays are clipped where solas-mi clips them) and real ray aiming to the stop
(`set_aiming("iterative")`, or "robust" where the iterative aim fails (the fisheye), as solas-mi aims at
stop points), its entrance pupil scaled so that its pupil's rim is the stop's (`fit_pupil`). Fields are
angles on y.
"""

from __future__ import annotations

import json
import sys
from importlib.metadata import version

import numpy as np

RIM_SLACK = 1e-9  # relative: a ray aimed at an aperture's rim passes (as in solas-mi's tracer)


def build(spec: dict):
    """An optiland Optic of one lens at one wavelength (`spec`, module docstring)."""
    from optiland.materials import IdealMaterial
    from optiland.optic import Optic
    from optiland.physical_apertures import RadialAperture

    optic = Optic()
    optic.surfaces.add(index=0, radius=np.inf, thickness=np.inf)
    for i, s in enumerate(spec["surfaces"], start=1):
        # an even asphere (optiland's coefficients multiply r², r⁴, ...; ours A4, A6, ...), its Newton to 1e-12 mm
        shape = (
            {"surface_type": "even_asphere", "conic": s["conic"], "coefficients": [0.0, *s["aspheric"]], "tol": 1e-12}
            if any(s.get("aspheric", ())) or s.get("conic")
            else {}
        )
        optic.surfaces.add(
            index=i,
            radius=s["radius"] or np.inf,
            thickness=s["thickness"],
            material=IdealMaterial(s["index_after"]),
            is_stop=s["stop"],
            aperture=RadialAperture(r_max=s["semi_diameter"] * (1 + RIM_SLACK)),
            **shape,
        )
    optic.surfaces.add(index=len(spec["surfaces"]) + 1)
    optic.set_aperture(aperture_type="EPD", value=spec["epd_mm"])
    optic.fields.set_type(field_type="angle")
    optic.fields.add(y=0.0)
    optic.fields.add(y=spec["max_field_deg"])
    optic.wavelengths.add(value=spec["wavelength_nm"] * 1e-3, is_primary=True)
    for mode in ("iterative", "robust"):  # the iterative aim's first guess fails at the fisheye's wide fields
        optic.ray_tracer.set_aiming(mode)
        optic.set_aperture(aperture_type="EPD", value=spec["epd_mm"])
        try:
            fit_pupil(optic, spec)
            optic.trace_generic(Hx=0.0, Hy=1.0, Px=0.0, Py=0.0, wavelength=spec["wavelength_nm"] * 1e-3)
        except ValueError:
            continue
        spec["aiming"] = mode
        break
    return optic


def fit_pupil(optic, spec: dict, rounds: int = 6) -> None:
    """Scale the EPD until optiland's pupil rim (Py = 1 on the axis, which its iterative aiming maps to a stop
    height in proportion) meets the stop's rim: solas-mi's normalised pupil coordinates are stop points, 1 at
    the rim, while optiland's are relative to the real ray through the paraxial entrance pupil's rim (on the
    Cooke triplet 1.5 % beyond the stop's rim, where the stop itself clips it)."""
    stop = next(i for i, s in enumerate(spec["surfaces"], start=1) if s["stop"])
    rim = next(s["semi_diameter"] for s in spec["surfaces"] if s["stop"])
    epd = spec["epd_mm"]
    for _ in range(rounds):
        optic.trace_generic(Hx=0.0, Hy=0.0, Px=0.0, Py=1.0, wavelength=spec["wavelength_nm"] * 1e-3)
        epd *= rim / float(np.asarray(optic.surfaces.y[stop])[0])
        optic.set_aperture(aperture_type="EPD", value=epd)
    spec["fitted_epd_mm"] = epd


def chief_and_fans(optic, spec: dict) -> dict:
    """Chief-ray heights (mm) at the fields, and ray fans: image-plane points (mm) of rays at pupil
    points Py (tangential, Px = 0) and Px (sagittal, Py = 0)."""
    wl = spec["wavelength_nm"] * 1e-3
    top = spec["max_field_deg"]
    out = {"chief_y_mm": [], "fan_y_mm": [], "fan_x_mm": []}
    t = np.array(spec["fan_pupil"])
    for f in spec["fields_deg"]:
        hy = f / top
        rays = optic.trace_generic(Hx=0.0, Hy=hy, Px=0.0, Py=0.0, wavelength=wl)
        out["chief_y_mm"].append(float(np.asarray(rays.y)[0]))
        ty = optic.trace_generic(Hx=np.zeros_like(t), Hy=np.full_like(t, hy), Px=np.zeros_like(t), Py=t, wavelength=wl)
        sx = optic.trace_generic(Hx=np.zeros_like(t), Hy=np.full_like(t, hy), Px=t, Py=np.zeros_like(t), wavelength=wl)
        out["fan_y_mm"].append(np.where(np.asarray(ty.i) > 0, np.asarray(ty.y), np.nan).tolist())
        out["fan_x_mm"].append(np.where(np.asarray(sx.i) > 0, np.asarray(sx.x), np.nan).tolist())
    return out


def distortion_and_curvature(optic, spec: dict) -> dict:
    """f-tan and f-theta distortion (%) and tangential/sagittal focus (mm from the image plane) at the
    fields of `spec["curve_fields_deg"]` (0 … the half field, evenly spaced)."""
    from optiland.analysis import FieldCurvature
    from optiland.analysis.distortion_strategies import create_distortion_model

    wl = spec["wavelength_nm"] * 1e-3
    hy = np.array(spec["curve_fields_deg"]) / spec["max_field_deg"]
    out = {}
    for kind in ("f-tan", "f-theta"):
        model = create_distortion_model("paraxial", distortion_type=kind)
        values = model.percent(model.compute(optic, np.zeros_like(hy[1:]), hy[1:], wl), signed=True)
        out[kind] = [0.0] + np.asarray(values).tolist()
    curvature = FieldCurvature(optic, wavelengths=[wl], num_points=len(hy))
    out["tangential_mm"], out["sagittal_mm"] = (np.asarray(v).tolist() for v in curvature.data[0])
    return out


def lateral_colour(optic, spec: dict) -> dict:
    """Chief-ray heights (mm) at the fields of `spec["curve_fields_deg"]` at each wavelength of
    `spec["colour"]` (each its own optic: constant-index media at that wavelength)."""
    heights = []
    for colour in spec["colour"]:
        surfaces = [{**s, "index_after": n} for s, n in zip(spec["surfaces"], colour["index_after"])]
        other = build({**spec, "surfaces": surfaces, "wavelength_nm": colour["wavelength_nm"]})
        hy = np.array(spec["curve_fields_deg"]) / spec["max_field_deg"]
        rays = other.trace_generic(
            Hx=np.zeros_like(hy),
            Hy=hy,
            Px=np.zeros_like(hy),
            Py=np.zeros_like(hy),
            wavelength=colour["wavelength_nm"] * 1e-3,
        )
        heights.append(np.where(np.asarray(rays.i) > 0, np.asarray(rays.y), np.nan).tolist())
    return {"colour_chief_y_mm": heights}


def wavefront(optic, spec: dict) -> dict:
    """Fringe Zernike terms 1-36 (waves) and OPD fans (waves) at the fields."""
    from optiland.wavefront import OPDFan, ZernikeOPD

    wl = spec["wavelength_nm"] * 1e-3
    out = {"zernike": [], "opd_fan_pupil": None, "opd_fan_y": [], "opd_fan_x": []}
    for f in spec["fields_deg"]:
        field = (0.0, f / spec["max_field_deg"])
        z = ZernikeOPD(
            optic, field=field, wavelength=wl, num_rings=spec["zernike_rings"], zernike_type="fringe", num_terms=36
        )
        out["zernike"].append(np.asarray(z.coeffs).tolist())
        out.setdefault("zernike_points", []).append(
            [np.asarray(z.x).tolist(), np.asarray(z.y).tolist(), np.asarray(z.z).tolist()]
        )
        fan = OPDFan(optic, fields=[field], wavelengths=[wl], num_rays=spec["opd_fan_rays"])
        data = fan.get_data(field, wl)
        opd = np.where(np.asarray(data.intensity) > 0, np.asarray(data.opd), np.nan)
        px, py = np.asarray(fan.distribution.x), np.asarray(fan.distribution.y)
        t = np.asarray(fan.pupil_coord)
        out["opd_fan_pupil"] = t.tolist()
        # the cross distribution: the y line (x = 0) and the x line (y = 0), the centre once
        out["opd_fan_y"].append([float(opd[(px == 0) & np.isclose(py, v)][0]) for v in t])
        out["opd_fan_x"].append([float(opd[(py == 0) & np.isclose(px, v)][0]) for v in t])
    return out


def mtf(optic, spec: dict) -> dict:
    """FFT MTF (tangential, sagittal) at the fields on optiland's own frequency axes (cycles/mm)."""
    from optiland.mtf import FFTMTF

    wl = spec["wavelength_nm"] * 1e-3
    fields = [(0.0, f / spec["max_field_deg"]) for f in spec["fields_deg"]]
    m = FFTMTF(optic, fields=fields, wavelength=wl, num_rays=spec["mtf_rays"], grid_size=spec["mtf_grid"])
    return {
        "freq_tangential": [np.asarray(v).tolist() for v in m.freq_tang],
        "freq_sagittal": [np.asarray(v).tolist() for v in m.freq_sag],
        "tangential": [np.asarray(v[0]).tolist() for v in m.mtf],
        "sagittal": [np.asarray(v[1]).tolist() for v in m.mtf],
    }


def main(argv: list[str]) -> int:
    with open(argv[0]) as f:
        request = json.load(f)
    results = {"optiland": version("optiland"), "numpy": version("numpy"), "lenses": {}}
    for name, spec in request["lenses"].items():
        optic = build(spec)
        entry = {}
        for part in (chief_and_fans, distortion_and_curvature, lateral_colour, wavefront, mtf):
            try:
                entry.update(part(optic, spec))
            except Exception as exc:  # one part failing on one lens is reported, the rest go on
                entry.setdefault("errors", []).append(f"{part.__name__}: {type(exc).__name__}: {exc}")
        entry["fitted_epd_mm"], entry["aiming"] = spec["fitted_epd_mm"], spec["aiming"]
        results["lenses"][name] = entry
        print(f"optiland: {name} done", file=sys.stderr, flush=True)
    with open(argv[1], "w") as f:
        json.dump(results, f)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
