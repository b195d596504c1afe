"""QE curves (`sensor.qe`): the effective QE matrix against integrals done by hand, the scalar model as
the degenerate curve (same frames), cross-talk, and a curve in a TOML file (inline or CSV)."""

import re
from dataclasses import replace

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.sensor.capture import capture, mean_electrons
from solas_mi.sensor.cfa import FILTERS
from solas_mi.sensor.exposure import LIGHT_SPEED, PLANCK
from solas_mi.sensor.files import describe, load_sensor
from solas_mi.sensor.model import SensorModel
from solas_mi.sensor.qe import BANDS_NM, QECurve, read_csv

R, G, B = (590.0, 780.0), (500.0, 590.0), (380.0, 500.0)  # the channels' bands, written out


def test_bands_are_the_renders():
    assert BANDS_NM == (R, G, B)


def test_linear_curve_against_the_hand_integral():
    """QE(λ) = a + bλ over 380–780 nm: Q[f, c] = ∫(a + bλ)λ dλ / ∫λ dλ = a + b (2/3)(hi³ − lo³)/(hi² − lo²)."""
    a, b = 0.1, 0.0008
    curve = QECurve.from_table({"wavelength_nm": [380, 780], "G": [a + b * 380, a + b * 780]})
    q = curve.effective_qe("G")
    for c, (lo, hi) in enumerate((R, G, B)):
        assert q[FILTERS.index("G"), c] == pytest.approx(a + b * (2 / 3) * (hi**3 - lo**3) / (hi**2 - lo**2), rel=1e-12)
    assert not q[[FILTERS.index(f) for f in "RBC"]].any()


def test_cross_talk_of_a_tent():
    """A red filter rising from 0 at 550 nm to 1 at 650 nm and back to 0 at 750 nm passes part of the
    green band: Q[R, G] = ∫_550^590 (λ − 550)/100 · λ dλ / ∫_500^590 λ dλ, and nothing of the blue."""
    curve = QECurve.from_table({"wavelength_nm": [550, 650, 750], "R": [0, 1, 0]})
    q = curve.effective_qe("R")[FILTERS.index("R")]
    lo, hi = 550.0, 590.0
    green = ((hi**3 - lo**3) / 3 - 550 * (hi**2 - lo**2) / 2) / 100 / ((590**2 - 500**2) / 2)
    # red band: the tent's ∫(QE λ) over 590–750 (rising to 650, falling to 750), by hand
    rise = ((650**3 - 590**3) / 3 - 550 * (650**2 - 590**2) / 2) / 100
    fall = (750 * (750**2 - 650**2) / 2 - (750**3 - 650**3) / 3) / 100
    red = (rise + fall) / ((780**2 - 590**2) / 2)
    assert q == pytest.approx([red, green, 0.0], rel=1e-12)
    # the electrons of a flat green field on an R site: Q[R, G] times the green band's photons
    model = SensorModel(
        cfa="RGGB",
        qe_curve=QECurve.from_table({"wavelength_nm": [550, 650, 750], "R": [0, 1, 0], "G": [1, 1, 1], "B": [1, 1, 1]}),
    )
    got = mean_electrons(model, np.broadcast_to([0.0, 2.0, 0.0], (2, 2, 3)), 0.01)[0, 0]
    photons = 2.0 * (model.pixel_pitch_um * 1e-6) ** 2 * 0.01 * 545e-9 / (PLANCK * LIGHT_SPEED)
    assert got == pytest.approx(green * photons, rel=1e-12)


def step_curve(qe: dict) -> QECurve:
    """QE η_f over the bands filter f collects (C: all three) and 0 elsewhere: the scalar model as a curve."""
    lam = [380, 500, 500, 590, 590, 780]
    band = {"R": [0, 0, 0, 0, 1, 1], "G": [0, 0, 1, 1, 0, 0], "B": [1, 1, 0, 0, 0, 0], "C": [1] * 6}
    return QECurve.from_table({"wavelength_nm": lam, **{f: [qe[f] * v for v in band[f]] for f in FILTERS}})


@pytest.mark.parametrize("cfa", ["RGGB", "RCCB", "RCCC"])
def test_scalar_model_is_the_degenerate_curve(cfa):
    """The scalar QEs at the bands' centres and the step curve of the same QEs give the same matrix and
    the same frames (photon shot noise, dark, read noise, PRNU, DSNU all on)."""
    qe = {"R": 0.45, "G": 0.6, "B": 0.4, "C": 0.85}
    scalar = SensorModel(
        cfa=cfa,
        qe_r=qe["R"],
        qe_g=qe["G"],
        qe_b=qe["B"],
        qe_c=qe["C"],
        wavelengths_nm=(685, 545, 440),
        prnu=0.02,
        dsnu_e=3.0,
    )
    curve = replace(scalar, qe_r=None, qe_g=None, qe_b=None, qe_c=None, wavelengths_nm=None, qe_curve=step_curve(qe))
    assert curve.channel_wavelengths_nm == scalar.wavelengths_nm
    assert np.allclose(curve.effective_qe(), scalar.effective_qe(), rtol=1e-14, atol=0)
    image = np.random.default_rng(0).uniform(0, 0.02, (48, 64, 3))
    assert np.array_equal(capture(curve, image, 0.01, seed=3), capture(scalar, image, 0.01, seed=3))


def test_curve_in_a_toml_file_inline_and_csv(tmp_path):
    table = {"wavelength_nm": [400, 550, 700], "R": [0.05, 0.1, 0.6], "G": [0.2, 0.7, 0.1], "B": [0.6, 0.2, 0.02]}
    (tmp_path / "qe.csv").write_text(
        "# measured\nwavelength_nm,R,G,B\n" + "".join(f"{w},{r},{g},{b}\n" for w, r, g, b in zip(*table.values()))
    )
    (tmp_path / "csv.toml").write_text('[sensor]\nqe_curve = "qe.csv"\n')
    (tmp_path / "inline.toml").write_text(
        "[sensor]\n[sensor.qe_curve]\n" + "".join(f"{k} = {v}\n" for k, v in table.items())
    )
    from_csv, inline = load_sensor(tmp_path / "csv.toml"), load_sensor(tmp_path / "inline.toml")
    assert from_csv == inline == SensorModel(qe_curve=QECurve.from_table(table))
    assert read_csv(tmp_path / "qe.csv") == inline.qe_curve
    meta = describe(inline)
    assert meta["qe_curve"] == table and meta["qe_r"] is None and SensorModel.from_dict(meta) == inline


@pytest.mark.parametrize(
    "sensor, message",
    [
        (
            "qe_r = 0.5\n[sensor.qe_curve]\nwavelength_nm = [400, 700]\nR = [0.5, 0.5]\nG = [0.5, 0.5]\nB = [0.5, 0.5]\n",
            "qe_curve and qe_r both given",
        ),
        (
            'cfa = "RCCB"\n[sensor.qe_curve]\nwavelength_nm = [400, 700]\nR = [0.5, 0.5]\nG = [0.5, 0.5]\nB = [0.5, 0.5]\n',
            "no column for filter\\(s\\) C",
        ),
        (
            "[sensor.qe_curve]\nwavelength_nm = [400, 700]\nR = [50, 60]\nG = [0.5, 0.5]\nB = [0.5, 0.5]\n",
            "filter R's quantum efficiency must be in \\[0, 1\\].*not %",
        ),
        (
            "[sensor.qe_curve]\nwavelength_nm = [700, 400]\nR = [0.5, 0.5]\nG = [0.5, 0.5]\nB = [0.5, 0.5]\n",
            "non-decreasing",
        ),
        (
            "[sensor.qe_curve]\nwavelength_nm = [400, 700]\nR = [0.5]\nG = [0.5, 0.5]\nB = [0.5, 0.5]\n",
            "all of one length",
        ),
        ("[sensor.qe_curve]\nwavelength = [400, 700]\nR = [0.5, 0.5]\n", "wavelength unknown or wavelength_nm missing"),
        ('qe_curve = "missing.csv"\n', "QE curve .*missing.csv.* does not exist"),
    ],
)
def test_bad_curves_are_named(tmp_path, sensor, message):
    (tmp_path / "s.toml").write_text("[sensor]\n" + sensor)
    with pytest.raises(SolasError, match=message) as info:
        load_sensor(tmp_path / "s.toml")
    assert re.search("s.toml", str(info.value))
