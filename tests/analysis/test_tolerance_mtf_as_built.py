"""A Monte Carlo with tolerances of the lens as built (`analysis.tolerance` with `Settings.mtf` "geometric"):
a sensor tilted about x puts each field's image point y·tan(tilt) behind the level sensor, so its MTF50 is
the level lens's through-focus MTF50 at that defocus (the route of tests/analysis/test_as_built_mtf.py);
the sensitivity table carries the new kinds; a run with an as-built kind says how it measured."""

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.analysis import tolerance
from solas_mi.analysis.as_built import mtf50_across_field
from solas_mi.analysis.through_focus import refocused
from solas_mi.optics import local_aim
from solas_mi.optics import tolerance as tol
from solas_mi.optics.placement import Placement

TILT_DEG = 0.5
GEOMETRIC = tolerance.Settings("none", 2, None, "geometric")  # fields −half, 0, +half


@pytest.fixture(scope="module")
def doublet():
    return Lens.load("solas-doublet")


@pytest.fixture(scope="module")
def spec(doublet):
    entry = {"kind": "sensor_tilt", "degrees": TILT_DEG, "distribution": "uniform"}
    return tol.spec_from_dict(doublet, {"tolerance": [entry]})


def test_a_sensor_tilt_samples_mtf50_at_plus_and_minus_field_moves_as_through_focus_predicts(doublet, spec):
    tilted = tol.alone(doublet, spec, 0, 1.0)
    assert tilted.image_placement == Placement(tilt_x=TILT_DEG)
    figures = tolerance.evaluate(tilted, GEOMETRIC)
    level = tolerance.evaluate(doublet, GEOMETRIC)["mtf50_cy_mm"]
    fields = np.array([[0.0, f] for f in figures["fields_deg"]])
    assert figures["fields_deg"] == (-doublet.field_deg, 0.0, doublet.field_deg)
    wl = doublet.primary_wavelength
    height = local_aim.chief_rays(tilted, fields, wl).image_xy[:, 1]
    through_focus = np.array(
        [
            mtf50_across_field(refocused(doublet, y * np.tan(np.radians(TILT_DEG))), f[None], wl)[0]
            for y, f in zip(height, fields)
        ]
    )
    sloped = figures["mtf50_cy_mm"]
    assert np.abs(sloped - through_focus).max() < 0.01 * np.nanmax(through_focus)
    change = sloped[[0, 2], 0] - level[[0, 2], 0]  # tangential at −field and +field
    assert np.sign(change[0]) == -np.sign(change[1]) and (np.abs(change) > 0.05 * level[[0, 2], 0]).all()


def test_the_sensitivity_table_has_the_sensor_tilt_terms(doublet, spec):
    rows = tolerance.sensitivity(doublet, spec, GEOMETRIC)
    assert [r["term"] for r in rows] == ["sensor_tilt_x", "sensor_tilt_y"]
    nominal = tolerance.worst(tolerance.evaluate(doublet, GEOMETRIC)["mtf50_cy_mm"])
    for row in rows:  # a tilt defocuses one side of the field or the other: the worst field gets worse
        assert row["worst_mtf50_cy_mm_minus"] < nominal and row["worst_mtf50_cy_mm_plus"] < nominal
        assert row["parameter_plus"] == pytest.approx(TILT_DEG, rel=1e-9)


def test_a_decentred_sample_is_focused_as_its_symmetric_part_by_the_compensator(doublet):
    """The Dr.Jit tracer the compensator uses takes one axis: it focuses the drawn lens without its decentre
    (here: the design), and the as-built lens is measured at that focus."""
    entry = {"kind": "decentre", "surfaces": [1, 2], "mm": 0.02}
    spec = tol.spec_from_dict(doublet, {"tolerance": [entry]})
    settings = tolerance.Settings("rms-spot", 2, None, "geometric")
    row = tolerance.sample(doublet, spec, 2, 0, settings)
    assert row["focus_shift_mm"] == tolerance.evaluate(doublet, settings)["focus_shift_mm"]
    assert row["lens"].surfaces[0].placement == Placement(decentre_x=row["deltas"][0], decentre_y=row["deltas"][1])
    assert np.isfinite(row["mtf50_cy_mm"]).all()
