"""`solas-mi thermal` (analysis.thermal, analysis.thermal_report): best focus against a scan of the RMS spot,
MTF50 against `mtf50-field` of the lens there, the sweep's rows against `Lens.at` and paraxial data; and
the lens at 20 °C and 101.325 kPa bit-identical to the lens as loaded."""

import csv
import json
import math

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.analysis import thermal
from solas_mi.errors import SolasError
from solas_mi.optics.paraxial import paraxial


def test_temperatures_include_both_ends():
    assert thermal.temperatures(-40.0, 105.0, 15.0) == [-40.0 + 15.0 * i for i in range(10)] + [105.0]
    assert thermal.temperatures(20.0, 20.0, 5.0) == [20.0]


@pytest.mark.parametrize(
    "start, stop, step",
    [(60.0, 20.0, 5.0), (20.0, 60.0, 0.0), (20.0, 60.0, math.nan), (-400.0, 20.0, 5.0), (20.0, 60.0, 1e-4)],
)
def test_bad_temperature_ranges_are_refused(start, stop, step):
    with pytest.raises(SolasError, match="temperature"):
        thermal.temperatures(start, stop, step)


def test_mtf50_is_the_lens_analysis_of_the_lens_there(doublet):
    """A row's MTF50 at the edge, as built, is `mtf50-field`'s at the edge of `Lens.at` that temperature."""
    from solas_mi.analysis.mtf_field import mtf50_field

    row = thermal.at_temperature(doublet, 70.0, 101.325, "aluminium", pupil_samples=64)
    there = mtf50_field(doublet.at(70.0, 101.325, "aluminium"), field_samples=2, pupil_samples=64)
    edge = row["mtf50_cy_mm"][thermal.FOCUS[0]][1.0]
    assert (edge["tangential"], edge["sagittal"]) == pytest.approx(tuple(there.mtf50_cy_mm[-1]), rel=1e-9)
    assert row["hash"] == doublet.at(70.0).hash


def test_best_focus_is_the_least_rms_spot(doublet):
    """The least-squares shift against a scan of the polychromatic RMS spot radius over image planes."""
    from dataclasses import replace

    from solas_mi.optics.spot import spot

    def rms(shift):
        lens = replace(
            doublet,
            surfaces=doublet.surfaces[:-1]
            + (replace(doublet.surfaces[-1], thickness=doublet.surfaces[-1].thickness + shift),),
        )
        hits = [spot(lens, (0.0, 0.0), w, density=thermal.SPOT_RINGS) for w in doublet.wavelengths_nm]
        return math.sqrt(np.mean(np.concatenate([h.x_um**2 + h.y_um**2 for h in hits])))

    shifts = np.linspace(0.3, 0.65, 36)
    scanned = shifts[int(np.argmin([rms(s) for s in shifts]))]
    assert thermal.best_focus_mm(doublet) == pytest.approx(scanned, abs=0.01)  # the scan's step


@pytest.mark.slow
def test_thermal_command(tmp_path, capsys):
    """Two temperatures: each row is `Lens.at` there (hash, EFL, BFD), refocusing does not lose MTF50 on axis,
    the CSV, JSON and PNG written."""
    from solas_mi.cli import main

    assert main(["thermal", "solas-doublet", "--from", "20", "--to", "60", "--step-c", "40", "-o", str(tmp_path)]) == 0
    assert "refocused" in capsys.readouterr().out
    lens = Lens.load("solas-doublet")
    doc = json.loads((tmp_path / "thermal.json").read_text())
    rows = list(csv.DictReader((tmp_path / "thermal.csv").open()))
    assert [float(r["temperature_c"]) for r in rows] == [20.0, 60.0] and (tmp_path / "thermal.png").stat().st_size
    for row, entry in zip(rows, doc["rows"]):
        there = lens.at(float(row["temperature_c"]))
        first = paraxial(there, there.primary_wavelength)
        assert entry["hash"] == there.hash
        assert float(row["efl_mm"]) == first.efl_mm and float(row["bfd_mm"]) == first.bfd_mm
        assert float(row["mtf50_refocused_axis_t_cy_mm"]) >= float(row["mtf50_as_built_axis_t_cy_mm"])
    assert doc["rows"][0]["hash"] == lens.hash


@pytest.mark.parametrize(
    "name", ["solas-doublet", "cooke-triplet", "double-gauss-50mm", "nikkor-fisheye", "wide-angle-22mm"]
)
def test_standard_conditions_are_bit_identical(name, tmp_path):
    """Each shipped lens as loaded, its file saying 20 °C and 101.325 kPa outright, and `Lens.at(20, 101.325)`
    with another mount: paraxial data, real chief rays and a polychromatic PSF equal to the last bit."""
    from solas_mi.optics.pupil import chief_rays
    from solas_mi.psf import psf

    lens = Lens.load(name)
    text = lens.save(tmp_path / "lens.toml").read_text()
    stated = tmp_path / "stated.toml"
    stated.write_text(text.replace("\nfield_deg =", "\ntemperature_c = 20.0\npressure_kpa = 101.325\nfield_deg ="))
    fields = [0.0, 0.7 * lens.field_deg, lens.field_deg]

    def figures(candidate):
        out = []
        for w in candidate.wavelengths_nm:
            out.append(
                np.array(
                    [v for _, v in sorted(paraxial(candidate, w, fields).as_dict().items()) if isinstance(v, float)]
                )
            )
            out.append(chief_rays(candidate, np.array([[0.0, f] for f in fields]), np.full(3, w)).image_xy)
        out.append(psf(candidate, (0.0, fields[1]), list(candidate.wavelengths_nm), pitch_um=1.0, size=48).data)
        return [np.asarray(a).tobytes() for a in out]

    reference = figures(lens)
    for other in (Lens.load(stated), lens.at(20.0, 101.325, mount="titanium")):
        assert other.hash == lens.hash and figures(other) == reference


def test_a_psf_says_where_its_lens_is(doublet):
    """A PSF's metadata names the lens's temperature and pressure where not 20 °C and 101.325 kPa."""
    from solas_mi.psf import psf

    hot = psf(doublet.at(60.0, 95.0), (0.0, 0.0), 531.0, pitch_um=2.0, size=16).meta
    plain = psf(doublet, (0.0, 0.0), 531.0, pitch_um=2.0, size=16).meta
    assert (hot["temperature_c"], hot["pressure_kpa"], hot["lens_hash"]) == (60.0, 95.0, doublet.at(60.0, 95.0).hash)
    assert "temperature_c" not in plain and "pressure_kpa" not in plain


def test_thermal_command_takes_pupil_samples(tmp_path):
    """--pupil-samples reaches the sweep as a number (it was passed on as the command line's text and refused)."""
    from solas_mi.cli import main

    argv = ["thermal", "solas-doublet", "--from", "20", "--to", "20", "--pupil-samples", "32", "-o", str(tmp_path)]
    assert main(argv) == 0
    assert json.loads((tmp_path / "thermal.json").read_text())["pupil_samples"] == 32
