"""The tolerance Monte Carlo (`analysis.tolerance`, `solas-mi tolerance`): the same seed gives the same lenses
and figures on any number of workers, each sample's figures are its lens file's, the yield and percentiles
are those of the samples, and the compensator refocuses."""

import csv
import json

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.analysis import tolerance
from solas_mi.analysis.mtf_field import mtf50_field
from solas_mi.analysis.thermal import best_focus_mm, refocused
from solas_mi.optics import tolerance as tol

SPEC = """
[compensator]
back_focus = "{compensator}"
[[tolerance]]
kind = "radius"
surfaces = [1, 6]
fringes = 3.0
[[tolerance]]
kind = "thickness"
surfaces = [2]
mm = 0.05
distribution = "uniform"
[[tolerance]]
kind = "index"
surfaces = [3]
delta = 5e-4
[[tolerance]]
kind = "despace"
mm = 0.02
"""
FAST = tolerance.Settings("none", field_samples=2, pupil_samples=32)


@pytest.fixture(scope="module")
def spec(cooke):
    return tol.spec_from_dict(
        cooke,
        {
            "tolerance": [
                {"kind": "radius", "surfaces": [1, 6], "fringes": 3.0},
                {"kind": "despace", "mm": 0.02},
            ]
        },
    )


def _figures(rows):
    return [(r["hash"], r["efl_mm"], r["focus_shift_mm"], r["mtf50_cy_mm"].tolist()) for r in rows]


def test_the_same_seed_gives_the_same_samples_on_any_number_of_workers(cooke, spec):
    one = tolerance.monte_carlo(cooke, spec, 3, 11, FAST, workers=1)
    two = tolerance.monte_carlo(cooke, spec, 3, 11, FAST, workers=2)
    assert _figures(one) == _figures(two)
    assert len({r["hash"] for r in one}) == 3 and cooke.hash not in {r["hash"] for r in one}


def test_a_sample_is_measured_as_the_lens_analysis_measures_its_lens(cooke, spec):
    """rms-spot: the shift is `best_focus_mm` of the drawn lens plus its despace (the sensor's error after
    focusing), the sample's lens is the drawn one with that image plane, its MTF50 `mtf50_field` of it."""
    settings = tolerance.Settings("rms-spot", field_samples=2, pupil_samples=32)
    row = tolerance.sample(cooke, spec, 5, 1, settings)
    drawn, deltas = tol.draw(cooke, spec, 5, 1)
    assert row["deltas"] == deltas and deltas[-1] != 0 and spec.terms[-1].kind == "despace"
    assert row["focus_shift_mm"] == best_focus_mm(drawn) + deltas[-1]
    assert row["hash"] == row["lens"].hash == refocused(drawn, row["focus_shift_mm"]).hash
    expected = mtf50_field(row["lens"], field_samples=2, pupil_samples=32)
    np.testing.assert_array_equal(row["mtf50_cy_mm"], expected.mtf50_cy_mm)


@pytest.mark.slow
def test_the_mtf50_compensator_finds_at_least_the_rms_focus_on_axis(cooke, spec):
    lens = tol.alone(cooke, spec, 2, 1.0)  # despaced 20 µm
    rms = tolerance.evaluate(lens, tolerance.Settings("rms-spot", 2, 32))
    best = tolerance.evaluate(lens, tolerance.Settings("mtf50", 2, 32))
    assert best["mtf50_cy_mm"][0, 0] >= rms["mtf50_cy_mm"][0, 0] - 1e-9
    assert abs(best["focus_shift_mm"] - rms["focus_shift_mm"]) < 0.1


def test_yield_and_percentiles_are_the_samples(cooke):
    rows = [{"mtf50_cy_mm": np.array([[30.0, 32.0], [v, 25.0]])} for v in (10.0, 20.0, 24.0, np.nan)]
    fraction, error = tolerance.yield_fraction(rows, 20.0)
    assert fraction == 0.75 and error == pytest.approx(np.sqrt(0.75 * 0.25 / 4))
    assert tolerance.percentiles(rows)[50][1, 0] == 20.0  # the NaN: an MTF that never falls to 1/2, left out


def test_tolerance_command(cooke, tmp_path, capsys):
    """Two samples: the lens files are the samples (hash), samples.csv and tolerance.json agree, the yield is
    the fraction of samples.csv's worst MTF50 at the limit, the sensitivity table has each term."""
    from solas_mi.cli import main

    spec_file = tmp_path / "tol.toml"
    spec_file.write_text(SPEC.format(compensator="none"))
    out = tmp_path / "out"
    argv = [
        "tolerance",
        "cooke-triplet",
        "--spec",
        str(spec_file),
        "--samples",
        "2",
        "--seed",
        "4",
        "-o",
        str(out),
        "--field-samples",
        "2",
        "--pupil-samples",
        "32",
        "--mtf50-limit",
        "19",
    ]
    assert main(argv) == 0
    assert "yield" in capsys.readouterr().out
    rows = list(csv.DictReader((out / "samples.csv").open()))
    doc = json.loads((out / "tolerance.json").read_text())
    for row in rows:
        lens = Lens.load(out / "lenses" / f"sample_{int(row['sample']):05d}.toml")
        assert (
            lens.hash == row["hash"] == tol.draw(cooke, tol.read_spec(cooke, spec_file), 4, int(row["sample"]))[0].hash
        )
    worst = [float(r["worst_mtf50_cy_mm"]) for r in rows]
    assert doc["yield"] == sum(w >= 19 for w in worst) / 2 and doc["samples"] == 2
    terms = [r["term"] for r in csv.DictReader((out / "sensitivity.csv").open())]
    assert terms == ["radius s1", "radius s6", "thickness s2", "index s3", "despace"]
    assert (out / "tolerance.png").stat().st_size


def test_tolerance_command_refuses_a_bad_entry_before_any_work(tmp_path, capsys):
    from solas_mi.cli import main

    spec_file = tmp_path / "tol.toml"
    spec_file.write_text('[[tolerance]]\nkind = "decentre"\nsurfaces = [1, 3]\nmm = 0.01\n')
    assert main(["tolerance", "cooke-triplet", "--spec", str(spec_file), "-o", str(tmp_path / "out")]) == 2
    assert "decentre" in capsys.readouterr().err and not (tmp_path / "out").exists()
