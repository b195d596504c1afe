"""Our nine doublet PSFs against KrakenOS's Fraunhofer PSFs (made by krakenos_reference.py).

Run: .venv/bin/python benchmarks/krakenos_crosscheck.py [out/kraken_ref/krakenos_psfs.npz]
Both sets: 160×160 at 0.5 µm, pixel centres (i − 79.5)·0.5 µm from each tool's own chief-ray point,
peak-normalised. Prints the RMSE per case (Markdown), for KrakenOS at the physical exit-pupil scale
(F/7.90) and at its native EFL/EPD scale (F/7.99), both without its tuning factors, and for both
tools against a direct Huygens–Fresnel sum over our 128² pupil (no Fraunhofer approximation; ~20 s a
case), which checks the diffraction step apart from the wavefront.
"""

from __future__ import annotations

import sys

import numpy as np

from solas_mi import Lens
from solas_mi.optics.pupil import pupil_function
from solas_mi.psf.base import normalize
from solas_mi.psf.fraunhofer import fraunhofer

CASES = [(f, w) for f in (0, -2, 2) for w in (486, 531, 656)]


def ours(lens: Lens, samples: int = 256) -> dict[tuple[int, int], np.ndarray]:
    fields = np.array([[0.0, f] for f, _ in CASES])
    waves = np.array([float(w) for _, w in CASES])
    pf = pupil_function(lens, fields, waves, samples)
    half_pixel = np.tile([0.25, -0.25], (len(CASES), 1))  # grid origin between the four centre pixels
    data = normalize(fraunhofer(pf, 0.5, 160, half_pixel), "peak")
    return {case: data[i] for i, case in enumerate(CASES)}


def huygens(lens: Lens, field_y: float, wavelength_nm: float, samples: int = 128) -> np.ndarray:
    """Peak-normalised |Σ a e^{ik(W + |P − Q| − R)} R/|P − Q||² over the sphere points Q, on the grid."""
    pf = pupil_function(lens, np.array([[0.0, field_y]]), np.array([wavelength_nm]), samples)
    a, b = np.meshgrid(pf.alpha[0] + pf.chief.sphere_point[0, 0], pf.beta[0] + pf.chief.sphere_point[0, 1])
    inside = pf.amplitude[0] > 0
    radius = pf.chief.sphere_radius[0]
    p0 = np.array([*pf.chief.image_xy[0], lens.image_z])
    q = np.stack(
        [
            p0[0] + radius * a[inside],
            p0[1] + radius * b[inside],
            p0[2] - radius * np.sqrt(1 - a[inside] ** 2 - b[inside] ** 2),
        ],
        axis=-1,
    )
    k = 2 * np.pi / (wavelength_nm * 1e-6)
    field = pf.amplitude[0][inside] * np.exp(1j * k * pf.opd_mm[0][inside])
    x = (np.arange(160) - 79.5) * 0.5e-3
    gx, gy = np.meshgrid(x, -x)
    p = np.stack([p0[0] + gx.ravel(), p0[1] + gy.ravel(), np.full(gx.size, p0[2])], axis=-1)
    u = np.empty(len(p), dtype=complex)
    for s in range(0, len(p), 512):
        d = np.linalg.norm(p[s : s + 512, None, :] - q[None], axis=-1)
        u[s : s + 512] = (np.exp(1j * k * (d - radius)) * (radius / d)) @ field
    return normalize((np.abs(u) ** 2).reshape(160, 160), "peak")


def main() -> None:
    ref = np.load(sys.argv[1] if len(sys.argv) > 1 else "out/kraken_ref/krakenos_psfs.npz")
    lens = Lens.load("solas-doublet")
    mine = ours(lens)
    coarse = ours(lens, 128)  # the Huygens sum's own sampling
    print(
        "| field (deg) | λ (nm) | ours vs KrakenOS F/7.90 | ours vs KrakenOS F/7.99 | ours vs Huygens "
        "| KrakenOS F/7.90 vs Huygens |"
    )
    print("|---|---|---|---|---|---|")
    rmse = lambda p, q: float(np.sqrt(np.mean((p - q) ** 2)))  # noqa: E731
    for f, w in CASES:
        key = f"f{f:+d}_w{w}"
        a, b, c = mine[(f, w)], ref[f"psf_{key}"], ref[f"native_psf_{key}"]
        h = huygens(lens, float(f), float(w))
        print(
            f"| {f:+d} | {w} | {rmse(a, b):.4f} | {rmse(a, c):.4f} | {rmse(coarse[(f, w)], h):.1e} | {rmse(b, h):.4f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
