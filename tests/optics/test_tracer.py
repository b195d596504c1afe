"""The Float64 sequential tracer: OPD exactness, unreachable fields, vignetting, TIR."""

from dataclasses import replace

import drjit as dr
import numpy as np
import pytest

from solas_mi import Lens, SolasError, spot
from solas_mi.optics import glass
from solas_mi.optics import pupil as P
from solas_mi.psf import psf

# DESIGN.md: RMS spot radius (µm) at the image plane, 0° and ±2°.


def test_opd_is_float64_exact(doublet):
    """On axis the wavefront is rotationally symmetric and smooth. In float32 the difference of two
    ~106 mm optical paths carries ~20 nm of noise (DESIGN.md); float64 must leave < 1e-6 waves."""
    pf = P.pupil_function(doublet, [[0.0, 0.0]], [531.0], 64)
    waves = pf.opd_mm[0] / 531e-6
    inside = pf.coverage[0] == 1.0
    assert np.abs(waves - waves.T)[inside].max() < 1e-6
    assert np.abs(waves - waves[::-1, :])[inside].max() < 1e-6
    # smoothness: W(ρ²) is a low-order polynomial; the fit residual is rounding noise only
    a, b = np.meshgrid(pf.alpha[0], pf.beta[0])
    rho2 = (a**2 + b**2)[inside]
    coef = np.polynomial.polynomial.polyfit(rho2 / rho2.max(), waves[inside], 6)
    residual = waves[inside] - np.polynomial.polynomial.polyval(rho2 / rho2.max(), coef)
    assert np.abs(residual).max() < 1e-6
    assert np.ptp(waves[inside]) > 1.0  # defocus of a few waves is really there


@pytest.mark.parametrize(
    "call",
    [
        lambda lens: psf(lens, (0, 30), 531.0),
        lambda lens: psf(lens, (0, 30), 531.0, method="geometric"),
        lambda lens: spot(lens, (0, 30), 531.0),
    ],
)
def test_unreachable_field_is_a_clear_error(doublet, call):
    """At 30° the chief ray through the stop centre exists (found by continuation where the paraxial guess
    loses it), but surface 1 blocks every ray of the field: a refusal naming the field and the cause."""
    with pytest.raises(
        SolasError,
        match=r"(no light reaches the image at field \(0, 30\) deg: every ray is blocked|"
        r"no ray of 531 nm through the pupil reaches the image for field \(0, 30\) deg: "
        r"every one is blocked)",
    ):
        call(doublet)


def test_vignetting_is_reported(doublet_spec):
    doublet_spec["surface"][0]["diameter"] = 10.0  # smaller than the 12.5 mm beam
    lens = Lens.from_dict(doublet_spec)
    pf = P.pupil_function(lens, [[0.0, 0.0], [0.0, 2.0]], [531.0, 531.0], 64)
    assert pf.vignetted_by[0] == [1]
    assert pf.transmission[0] == pytest.approx((10.0 / 12.5075) ** 2, rel=0.01)
    s = spot(lens, (0.0, 2.0), 531.0)
    assert s.vignetted > 0


def test_total_internal_reflection_is_flagged():
    """Inside N-SF11 (n = 1.79) the critical angle is 34°; at y = 4 mm on an R = 5 mm exit surface
    the incidence is 53°, at y = 0 it is 0°."""
    from solas_mi.optics import tracer as T

    spec = {
        "surface": [
            {"radius": 0.0, "thickness": 5.0, "diameter": 20.0, "material": "N-SF11", "stop": True},
            {"radius": 5.0, "thickness": 10.0, "diameter": 9.0, "material": "AIR"},
        ]
    }
    lens = Lens.from_dict(spec)
    zero = T.F([0.0, 0.0])
    tr = T.trace(lens, T.launch(lens, zero, zero, zero, T.F([0.0, 4.0])), T.F(0.55))
    assert list(np.asarray(tr.tir)) == [False, True]
    assert list(np.asarray(tr.ok)) == [True, False]


def _psf_kernels(lens) -> set:
    """The hashes of the Dr.Jit kernels that a diffraction PSF of `lens` runs."""
    dr.kernel_history()  # start from an empty history
    psf(lens, (0, 10), 531.0, size=32)
    return {k["hash"] for k in dr.kernel_history() if k.get("type") == dr.KernelType.JIT}


def _thicker(lens):
    """`lens` with its first air gap 0.01 mm longer."""
    surfaces = list(lens.surfaces)
    surfaces[1] = replace(surfaces[1], thickness=surfaces[1].thickness + 0.01)
    return replace(lens, surfaces=tuple(surfaces))


def _reglazed(lens, glass_of):
    """`lens` with each glass g of its surfaces replaced by `glass_of(g)` (air kept)."""
    return replace(
        lens, surfaces=tuple(s if s.glass.kind == "air" else replace(s, glass=glass_of(s.glass)) for s in lens.surfaces)
    )


def _irregular(lens, a4: float):
    """`lens` with an r⁴ sag term `a4` (mm⁻³) on its first surface (a tolerance's irregularity)."""
    surfaces = list(lens.surfaces)
    surfaces[0] = replace(surfaces[0], aspheric=(a4,))
    return replace(lens, surfaces=tuple(surfaces))


# (the lens the kernels are first compiled for, the lens that must reuse them)
_SAME_KERNELS = {
    "thickness": (lambda lens: lens, _thicker),
    "melt": (lambda lens: lens, lambda lens: _reglazed(lens, lambda g: replace(g, melt=(5e-4, -0.2)))),
    "another melt": (
        lambda lens: _reglazed(lens, lambda g: replace(g, melt=(5e-4, -0.2))),
        lambda lens: _reglazed(lens, lambda g: replace(g, melt=(-3e-4, 0.1))),
    ),
    "another glass": (
        lambda lens: lens,
        lambda lens: _reglazed(
            lens, lambda g: glass.resolve("SCHOTT:N-SK4") if g.name.endswith("N-SK16") else glass.resolve("SCHOTT:SF5")
        ),
    ),
    "temperature": (lambda lens: lens.at(60.0), lambda lens: lens.at(-20.0, 90.0)),
    "irregularity": (lambda lens: _irregular(lens, 2e-7), lambda lens: _irregular(lens, -3e-7)),
}


@pytest.mark.parametrize("change", sorted(_SAME_KERNELS))
def test_a_lens_drawn_anew_runs_the_kernels_of_its_nominal(triplet, change):
    """A lens's numbers (vertex positions, its image plane, its pupil's size, its glasses' dispersion
    coefficients, a melt's terms, thermal data and temperature, its aspheric terms) enter the kernels as opaque inputs, not
    literals: a tolerance sample (a thickness, a melt, another glass of the same formula, an irregularity) or another
    temperature reuses the first lens's compiled kernels instead of compiling its own (0.65 s against
    0.06 s of CPU for a two-field OTF of the Cooke triplet)."""
    first, then = _SAME_KERNELS[change]
    flag = dr.flag(dr.JitFlag.KernelHistory)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        nominal = _psf_kernels(first(triplet))
        drawn = _psf_kernels(then(triplet))
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, flag)
    assert nominal and drawn == nominal, f"{len(drawn - nominal)} kernels of {len(drawn)} new"
