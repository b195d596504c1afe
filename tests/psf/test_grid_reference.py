"""The fast PSF grid (rays aimed coarse to fine, pupil cells and DFT kernels in Dr.Jit, complex64 matrix
products in threads, mirrored nodes, the error estimate on a subset) against the grid's method done the
plain way, node by node at each node's own field: every pupil ray aimed from the stop rim's affine map
with finite-difference Jacobians, the cells in NumPy (`numpy.gradient`), the DFT in complex128, no
symmetry. The two agree within 1e-6 of each PSF's peak."""

import math

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.optics import pupil as P
from solas_mi.optics import tracer as T
from solas_mi.optics.aiming import Bundle, aim
from solas_mi.optics.pupil_grid import sphere_target
from solas_mi.psf import psf_grid
from solas_mi.psf.base import grid_offsets

PUPIL = 64


def plain_pupil(lens, field, wavelength, n):
    """One field's pupil function on an n² (α, β) grid, as the Fraunhofer method defines it."""
    fields, waves = np.array([field], dtype=float), np.array([wavelength], dtype=float)
    chief = P.chief_rays(lens, fields, waves)
    rim = Bundle(lens, fields, waves, P.RIM_RAYS)
    target = sphere_target(lens, rim, chief)
    rex, rey, rtr, rok = P.stop_rim(rim, chief, accept=lambda tr: target(tr)[2])
    ra, rb = (v - chief.sphere_point[0, i] for i, v in enumerate(T.to_numpy(*target(rtr)[:2])))
    ok_rim = rok[0]
    grids = []
    for rel in (ra[ok_rim], rb[ok_rim]):
        half = 0.5 * (rel.max() - rel.min()) * (1.0 + 2.0 / n) * 1.01
        grids.append(0.5 * (rel.max() + rel.min()) + half * np.linspace(-1.0, 1.0, n))
    alpha, beta = grids
    design = np.stack([np.ones(ok_rim.sum()), ra[ok_rim], rb[ok_rim]], axis=1)
    affine = np.linalg.lstsq(design, np.stack([rex[0, ok_rim], rey[0, ok_rim]], axis=1), rcond=None)[0]
    ta, tb = np.meshgrid(alpha, beta)  # [β, α]
    g = Bundle(lens, fields, waves, n * n)
    start = affine[0] + np.outer(ta.ravel(), affine[1]) + np.outer(tb.ravel(), affine[2])
    ex, ey, tr, conv = aim(
        g,
        sphere_target(lens, g, chief),
        T.array(start[:, 0]),
        T.array(start[:, 1]),
        T.array(ta.ravel() + chief.sphere_point[0, 0]),
        T.array(tb.ravel() + chief.sphere_point[0, 1]),
    )
    _, _, _, opl, hit = T.to_sphere(
        tr, chief.image_xy[0, 0], chief.image_xy[0, 1], lens.image_z, chief.sphere_radius[0]
    )
    opl, ok, clipped, sx, sy, ex, ey = (
        v.reshape(n, n) for v in T.to_numpy(opl, conv & hit, tr.clipped_by, tr.stop_x, tr.stop_y, ex, ey)
    )
    da, db = alpha[1] - alpha[0], beta[1] - beta[0]

    def jacobian(u, w):
        du_db, du_da = np.gradient(u)
        dw_db, dw_da = np.gradient(w)
        return np.abs(du_da * dw_db - du_db * dw_da) / (da * db)

    power = P.entrance_power(lens, fields, waves, ex[None], ey[None])[0] * jacobian(ex, ey)
    margin = lens.surfaces[lens.stop_index].semi_diameter - np.hypot(sx, sy)
    coverage = np.clip(0.5 + margin / np.maximum(np.sqrt(jacobian(sx, sy) * da * db), 1e-300), 0.0, 1.0)
    coverage[((clipped != 0) & (clipped != lens.stop_index + 1)) | ~ok | ~np.isfinite(power)] = 0.0
    opd = np.where(coverage > 0, opl - chief.opl[0], 0.0)
    amplitude = np.sqrt(np.where(coverage > 0, power, 0.0)) * coverage
    return alpha, beta, amplitude * np.exp(2j * math.pi * opd / (wavelength * 1e-6)), chief


def plain_psf(lens, field, wavelength, pitch_um, size, n=PUPIL):
    """|DFT|² of the plain pupil function on size² pixels about the chief ray, in 1/µm²."""
    alpha, beta, pupil, chief = plain_pupil(lens, field, wavelength, n)
    lam = wavelength * 1e-6 / chief.n_image[0]
    offs = grid_offsets(size, pitch_um) * 1e-3
    kx = np.exp(-2j * math.pi / lam * np.outer(alpha, offs))
    ky = np.exp(-2j * math.pi / lam * np.outer(-offs, beta))
    u = ky @ pupil @ kx
    return np.abs(u) ** 2 * ((alpha[1] - alpha[0]) * (beta[1] - beta[0]) / lam) ** 2 * 1e-6


@pytest.mark.parametrize(
    "lens_name, options, nodes",
    [
        # mirrored and transposed nodes of a centred grid, both wavelengths
        (
            "solas-doublet",
            dict(grid=(4, 5), wavelengths_nm=[656.0, 486.0], pitch_um=0.5, size=48),
            [(0, 0, 0), (0, 3, 4), (1, 1, 2), (1, 2, 1), (0, 3, 0)],
        ),
        # a vignetted lens: rays lost at the coarse levels, aimed from the affine map
        (
            "cooke-triplet",
            dict(
                grid=(3, 3),
                wavelengths_nm=[587.56],
                field_range_deg=(24.0, 16.0),
                field_sampling="edges",
                pitch_um=4.0,
                size=32,
            ),
            [(0, 0, 0), (0, 1, 2), (0, 2, 1)],
        ),
    ],
)
def test_the_grid_equals_the_plain_method(lens_name, options, nodes):
    lens = Lens.load(lens_name)
    _check_nodes(lens, options, nodes)


def test_a_finite_object(doublet):
    """A near object: each ray's power carries its obliquity (computed in Dr.Jit by the grid)."""
    from dataclasses import replace

    _check_nodes(
        replace(doublet, object_distance=600.0),
        dict(grid=(2, 2), wavelengths_nm=[531.0], pitch_um=1.0, size=48),
        [(0, 0, 0), (0, 1, 1)],
    )


def _check_nodes(lens, options, nodes):
    grid = psf_grid(lens, pupil_samples=PUPIL, normalization="none", **options)
    for k, row, col in nodes:
        ref = plain_psf(lens, grid.fields_deg[row, col], grid.wavelengths_nm[k], grid.pitch_um, grid.size)
        got = grid.data[k, row, col]
        assert np.abs(got - ref).max() < 1e-6 * ref.max(), (k, row, col)
