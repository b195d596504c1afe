"""`GridSpec`: the one definition of a PSF grid's options; the public arguments of `psf`, `psf_grid`
and `degrade` checked with one clear error each; the PSF method registry."""

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.psf import psf, psf_grid
from solas_mi.psf.spec import GridSpec

TINY = dict(grid=(1, 2), size=16, pitch_um=2.0, pupil_samples=16)


def test_a_bare_number_is_one_wavelength(doublet):
    one = psf_grid(doublet, wavelengths_nm=531, **TINY)
    listed = psf_grid(doublet, wavelengths_nm=[531.0], **TINY)
    assert one.wavelengths_nm == (531.0,) and np.array_equal(one.data, listed.data)


def test_a_spec_and_keywords_give_the_same_grid(doublet):
    spec = GridSpec(wavelengths_nm=(531.0,), **TINY)
    assert np.array_equal(psf_grid(doublet, spec).data, psf_grid(doublet, wavelengths_nm=531.0, **TINY).data)
    assert psf_grid(doublet, spec, size=20).size == 20  # keywords override the spec's fields
    assert psf_grid(doublet, spec).meta["grid_spec"] == spec.canonical()


def test_the_canonical_form_keeps_only_what_makes_the_grid():
    assert "rays" not in GridSpec().canonical() and "pupil_samples" in GridSpec().canonical()
    assert "pupil_samples" not in GridSpec(method="geometric").canonical()
    assert GridSpec(rays=8).key("h") == GridSpec().key("h") != GridSpec().key("other lens")
    sensor = GridSpec(layout="sensor", sensor_mm=(6, 4)).canonical()
    assert sensor["sensor_mm"] == [6.0, 4.0] and "field_range_deg" not in sensor
    assert GridSpec(field_range_deg=2).field_range_deg == (2.0, 2.0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(wavelengths_nm="531"), r"wavelengths '531' must be a number or a sequence"),
        (dict(wavelengths_nm=[531, "x"]), r"wavelength \(nm\) 'x' must be a finite number"),
        (dict(wavelengths_nm=[]), r"wavelengths \[\] must be one or more positive numbers"),
        (dict(grid="8x8"), r"grid '8x8' must be \(rows, columns\)"),
        (dict(grid=(2.0, 3)), r"grid \(2.0, 3\) must be \(rows, columns\)"),
        (dict(layout="polar"), "grid layout 'polar' must be one of field, sensor"),
        (dict(sensor_mm=(6, 4)), r"sensor size \(6, 4\) mm is for layout sensor"),
        (dict(layout="sensor", field_range_deg=2.0), "field range 2.0 deg is for layout field"),
        (dict(pitch_um="0.5"), "PSF pitch '0.5' µm must be a positive number"),
        (dict(pitch_um=True), "PSF pitch True µm must be a positive number"),
        (dict(size=16.0), "PSF size 16.0 must be an integer"),
        (dict(method=None), "PSF method None must be one of fraunhofer, geometric"),
        (dict(method="geometric", rays=1), "rays 1 must be an integer from 2 to 4096"),
        (dict(normalization=0), "normalization 0 must be one of"),
        (dict(auto_window="yes"), "auto_window 'yes' must be True or False"),
    ],
)
def test_bad_spec_arguments(doublet, kwargs, match):
    with pytest.raises(SolasError, match=match):
        GridSpec(**kwargs)
    with pytest.raises(SolasError, match=match):
        psf_grid(doublet, **kwargs)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda d: psf_grid("solas-doublet"), "lens 'solas-doublet' must be a Lens"),
        (lambda d: psf_grid(d, {"grid": (2, 2)}), "must be a GridSpec"),
        (lambda d: psf(None, (0, 0), 531.0), "lens None must be a Lens"),
        (lambda d: psf(d, (0, 0), "531"), "wavelength '531' nm must be a positive number"),
        (lambda d: psf(d, (0, 0), [531.0, 486.0], weights="1,1"), "weights '1,1' must be 2 non-negative numbers"),
        (lambda d: psf(d, (0, 0), 531.0, size=16, pupil_sample=16), "PSF options pupil_sample are unknown"),
        (lambda d: psf(d, (0, 0), 531.0, method=["geometric"]), r"PSF method \['geometric'\] must be one of"),
    ],
)
def test_bad_public_arguments(doublet, call, match):
    with pytest.raises(SolasError, match=match):
        call(doublet)


def test_degrade_checks_its_arguments():
    from solas_mi.convolution.methods import degrade

    with pytest.raises(SolasError, match="grid int must be a PSFGrid or the path of its EXR file"):
        degrade(np.ones((4, 4)), 5)
    with pytest.raises(SolasError, match="convolution method None must be one of interp, patch"):
        degrade(np.ones((4, 4)), "g.exr", None)


def test_each_method_has_its_own_options_and_the_render_stage_registers_its_own():
    from solas_mi.psf.registry import METHODS, method_options

    assert method_options("fraunhofer", {"pupil_samples": 64, "rays": 9}) == {"pupil_samples": 64}
    assert method_options("geometric", {}) == {"rays": 512}
    assert "render" in METHODS and METHODS["render"].options == METHODS["geometric"].options


@pytest.mark.parametrize(
    "text, says", [("0:5", "depth node count 0"), ("3:-1", "nearest distance -1.0 m"), ("x:5", "must be N:NEAR")]
)
def test_distances_text_names_what_is_wrong(text, says):
    from solas_mi.psf.spec import parse_distances

    with pytest.raises(SolasError, match=says):
        parse_distances(text)
