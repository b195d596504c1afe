"""The lens as built against optiland, an independent tracer: the Cooke triplet with its middle element
decentred (0.1, −0.05 mm) and tilted (0.4°, −0.3°) by a coordinate break before it and its reverse after
it, 25 real rays at five fields in two dimensions traced by solas-mi's NumPy tracer in each surface's frame
(`optics.local_trace`) and by optiland with each surface placed absolutely (its origin and the x-y-z
angles of its axes, `optics.placement.frames`); the image points compared. Two steps, two Pythons (the
second never imports solas-mi, the first never optiland):

    .venv/bin/python benchmarks/asbuilt_optiland.py request asbuilt.json
    .optiland-venv/bin/python benchmarks/asbuilt_optiland.py compare asbuilt.json

Measured (optiland 0.6.3, NumPy Float64): 25 of 25 rays through both, image points within 1.6e-14 mm.
"""

from __future__ import annotations

import json
import sys

import numpy as np

FIELDS_DEG = [(0, 0), (0, 14), (0, -14), (10, 10), (-12, 5)]
PUPIL_MM = [(0, 0), (1.5, 0), (0, 1.5), (-1.2, -0.8), (0.7, -1.4)]  # where each ray crosses z = 10 mm


def request(path: str) -> None:
    """Write the lens as built, its rays and solas-mi's trace of them to `path`."""
    from as_built_lens import cooke_as_built
    from scipy.spatial.transform import Rotation

    from solas_mi.optics import local_trace
    from solas_mi.optics.placement import frames

    lens, wavelength = cooke_as_built(toroid=False), 587.5618
    placed = frames(lens.surfaces)
    angles = [list(Rotation.from_matrix(axes).as_euler("xyz")) for _, axes in placed]  # axes = Rz Ry Rx
    rows = [
        {
            "origin": o.tolist(),
            "angles": a,
            "radius": s.radius,
            "conic": s.conic,
            "stop": s.stop,
            "index_after": float(s.glass.index(wavelength)),
            "semi_diameter": s.semi_diameter,
        }
        for s, (o, _), a in zip(lens.surfaces, placed, angles)
    ]
    points, directions = [], []
    for fx, fy in FIELDS_DEG:
        d = np.array([np.tan(np.radians(fx)), np.tan(np.radians(fy)), 1.0])
        d /= np.linalg.norm(d)
        for px, py in PUPIL_MM:
            points.append(np.array([px, py, 10.0]) - 30.0 * d)
            directions.append(d)
    traced = local_trace.trace(lens, local_trace.bundle(np.array(points), np.array(directions)), wavelength)
    out = {
        "wavelength_um": wavelength * 1e-3,
        "surfaces": rows,
        "image": {"origin": placed[-1][0].tolist(), "angles": angles[-1]},
        "rays": {"points": np.array(points).tolist(), "directions": np.array(directions).tolist()},
        "solas": {"x": traced.x.tolist(), "y": traced.y.tolist(), "z": traced.z.tolist(), "ok": traced.ok.tolist()},
    }
    with open(path, "w", encoding="utf-8") as f:
        json.dump(out, f)


def compare(path: str) -> None:
    """Trace the request's rays with optiland and print how far its image points lie from solas-mi's."""
    from optiland.materials import IdealMaterial
    from optiland.optic import Optic
    from optiland.physical_apertures import RadialAperture
    from optiland.rays import RealRays

    with open(path, encoding="utf-8") as f:
        req = json.load(f)
    optic = Optic()
    optic.surfaces.add(index=0, radius=np.inf, thickness=np.inf)
    for i, s in enumerate(req["surfaces"], start=1):
        (x, y, z), (rx, ry, rz) = s["origin"], s["angles"]
        optic.surfaces.add(
            index=i,
            radius=s["radius"] or np.inf,
            conic=s["conic"],
            x=x,
            y=y,
            z=z,
            rx=rx,
            ry=ry,
            rz=rz,
            material=IdealMaterial(s["index_after"]),
            is_stop=s["stop"],
            aperture=RadialAperture(r_max=s["semi_diameter"] * (1 + 1e-9)),
        )
    (x, y, z), (rx, ry, rz) = req["image"]["origin"], req["image"]["angles"]
    optic.surfaces.add(index=len(req["surfaces"]) + 1, x=x, y=y, z=z, rx=rx, ry=ry, rz=rz)
    p, d = np.array(req["rays"]["points"]), np.array(req["rays"]["directions"])
    n = len(p)
    rays = RealRays(p[:, 0], p[:, 1], p[:, 2], d[:, 0], d[:, 1], d[:, 2], np.ones(n), np.full(n, req["wavelength_um"]))
    optic.surfaces.trace(rays, skip=1)
    sol = req["solas"]
    passed = np.asarray(rays.i) > 0
    ok = np.array(sol["ok"]) & passed
    ours = np.array([sol["x"], sol["y"], sol["z"]])
    theirs = np.array([np.asarray(rays.x), np.asarray(rays.y), np.asarray(rays.z)])
    print(
        f"rays through both: {int(ok.sum())} of {n} (solas-mi {int(np.sum(sol['ok']))}, optiland "
        f"{int(passed.sum())}); image points within {np.abs(ours - theirs)[:, ok].max():.2e} mm"
    )


if __name__ == "__main__":
    {"request": request, "compare": compare}[sys.argv[1]](sys.argv[2])
