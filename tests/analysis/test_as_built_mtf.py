"""MTF50 across the field of the lens as built (`analysis.as_built`): the doublet with its sensor tilted 0.5°
about x. Each field's image point lies y·tan(0.5°) behind the untilted image plane, so its MTF50 is the
through-focus MTF50 of the untilted lens at that defocus: it falls on the side the through-focus curve says
and rises on the other."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from solas_mi import Lens
from solas_mi.analysis.as_built import geometric_mtf, mtf50_across_field
from solas_mi.analysis.through_focus import refocused
from solas_mi.optics import local_aim
from solas_mi.optics.placement import Placement

TILT_DEG = 0.5


def test_a_tilted_sensors_mtf50_falls_on_one_side_and_rises_on_the_other_as_through_focus_predicts():
    lens = Lens.load("solas-doublet")
    wl = lens.primary_wavelength
    tilted = replace(lens, image_placement=Placement(tilt_x=TILT_DEG))
    fields = np.array([[0.0, -0.7 * lens.field_deg], [0.0, 0.7 * lens.field_deg]])
    level, sloped = mtf50_across_field(lens, fields, wl), mtf50_across_field(tilted, fields, wl)
    height = local_aim.chief_rays(tilted, fields, wl).image_xy[:, 1]
    through_focus = np.array(
        [
            mtf50_across_field(refocused(lens, y * np.tan(np.radians(TILT_DEG))), f[None], wl)[0]
            for y, f in zip(height, fields)
        ]
    )
    assert np.abs(sloped - through_focus).max() < 0.01 * through_focus.max()  # measured: 0.3 %
    change, predicted = sloped - level, through_focus - level
    assert (np.sign(change) == np.sign(predicted)).all() and (np.abs(change) > 0.05 * level).all()
    assert np.sign(change[0, 0]) == -np.sign(change[1, 0])  # tangential: one side falls, the other rises
    assert np.abs(level[0] - level[1]).max() < 1e-9 * level.max()  # the untilted sensor's sides agree


def test_the_geometric_mtf_of_a_perfect_focus_is_one_and_its_directions_turn_with_the_field():
    """An ideal lens puts every ray on its chief ray's point: its spot's MTF is 1 at every frequency. A lens
    symmetric about its axis has at (x, 0) the tangential and sagittal MTF it has at (0, x): the directions
    turn with the field."""
    ideal = Lens.from_dict(
        {
            "name": "ideal",
            "surface": [{"radius": 0.0, "focal_length": 40.0, "thickness": 40.0, "diameter": 10.0, "stop": True}],
        }
    )
    assert np.abs(geometric_mtf(ideal, (3.0, -4.0), 550.0, [10.0, 100.0]) - 1.0).max() < 1e-9
    lens = Lens.load("solas-doublet")
    freq = [10.0, 30.0, 60.0]
    along_y, along_x = (geometric_mtf(lens, f, lens.primary_wavelength, freq) for f in ((0.0, 1.4), (1.4, 0.0)))
    assert np.abs(along_y - along_x).max() < 1e-9  # measured: 7e-15 and np.abs(along_y[0] - along_y[1]).max() > 0.05
