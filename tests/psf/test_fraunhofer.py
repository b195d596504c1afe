"""Fraunhofer PSFs against physics: the Airy pattern, discrete Parseval, convergence in pupil sampling."""

import math

import numpy as np
import pytest
from scipy.special import j1

from solas_mi import Lens, paraxial
from solas_mi.optics import pupil as P
from solas_mi.psf import psf
from solas_mi.psf.fraunhofer import fraunhofer
from solas_mi.psf.registry import DEFAULT_PUPIL_SAMPLES


@pytest.fixture(scope="module")
def slow_singlet():
    """A plano-convex N-BK7 singlet stopped to 2 mm (f/50), image plane at its paraxial focus:
    diffraction-limited, so its PSF is the Airy pattern."""
    spec = {
        "surface": [
            {"radius": 51.68, "thickness": 3.0, "diameter": 2.0, "material": "N-BK7", "stop": True},
            {"radius": 0.0, "thickness": 100.0, "diameter": 10.0, "material": "AIR"},
        ]
    }
    bfd = paraxial(Lens.from_dict(spec), 550.0).bfd_mm
    spec["surface"][1]["thickness"] = bfd
    return Lens.from_dict(spec)


def test_airy_pattern(slow_singlet):
    p = psf(slow_singlet, (0, 0), 550.0, pitch_um=1.0, size=121, normalization="peak")
    rim = P.stop_rim(
        P.Bundle(slow_singlet, np.zeros((1, 2)), np.array([550.0]), P.RIM_RAYS),
        P.chief_rays(slow_singlet, [[0.0, 0.0]], [550.0]),
    )[2]
    na = float(np.max(np.asarray(rim.rays.dy)))  # sine of the real marginal ray's angle
    x, y = np.meshgrid(p.x_um, p.y_um)
    arg = 2 * math.pi / 0.55 * na * np.hypot(x, y)
    airy = np.where(arg > 0, (2 * j1(arg) / np.where(arg > 0, arg, 1)) ** 2, 1.0)
    rmse = np.sqrt(np.mean((p.data - airy) ** 2))
    assert rmse < 1e-3
    assert 1.22 * 0.55 / (2 * na) == pytest.approx(33.5, rel=0.02)  # f/50: first dark ring at 33.5 µm


def test_parseval_discrete(doublet):
    """On a grid spanning exactly one period λ/Δα of the pupil DFT, Σ|U|² equals Σ|a|² dα dβ."""
    n = 64
    pf = P.pupil_function(doublet, [[0.0, 0.0]], [531.0], n)
    da = pf.alpha[0, 1] - pf.alpha[0, 0]
    assert pf.beta[0, 1] - pf.beta[0, 0] == pytest.approx(da)
    pitch_um = 531e-6 / (n * da) * 1e3
    psf = fraunhofer(pf, pitch_um, n)[0]
    assert psf.sum() * pitch_um**2 == pytest.approx(float(np.sum(pf.amplitude**2) * pf.cell_area[0]), rel=1e-5)


@pytest.mark.parametrize("field", [0.0, 2.0])
def test_pupil_sampling_converges(doublet, field):
    """Doubling the default pupil sampling changes the PSF by < 1e-3 RMSE of the peak."""
    a = psf(doublet, (0, field), 486.0, pupil_samples=DEFAULT_PUPIL_SAMPLES).data
    b = psf(doublet, (0, field), 486.0, pupil_samples=2 * DEFAULT_PUPIL_SAMPLES).data
    assert np.sqrt(np.mean((a - b) ** 2)) < 1e-3 * b.max()
