"""`lens info` and metadata of the lens as built: paraxial data said to be about the nominal axis where a
break decentres or tilts a surface or the sensor, the real chief rays aimed by the NumPy tracer."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from solas_mi import Lens
from solas_mi.cli import main
from solas_mi.optics import local_aim, notes, placement
from solas_mi.optics.placement import Placement


def test_the_paraxial_note_names_what_is_decentred_or_tilted_and_only_that():
    lens = Lens.load("solas-doublet")
    surfaces = tuple(replace(s, placement=Placement()) for s in lens.surfaces)
    assert notes.metadata(lens) == notes.metadata(replace(lens, surfaces=surfaces, image_placement=Placement())) == {}
    moved = (surfaces[0], replace(surfaces[1], placement=Placement(decentre_y=0.1)), *surfaces[2:])
    for kind, expected in (
        (replace(lens, surfaces=moved), "surface 2 decentred or tilted"),
        (replace(lens, image_placement=Placement(tilt_x=0.5)), "the sensor decentred or tilted"),
    ):
        note = placement.metadata(kind)["paraxial_axis"]
        assert note.endswith(f"approximates the lens as built: {expected}") and "nominal axis" in note


def test_lens_info_of_a_tilted_sensor_notes_the_axis_and_aims_its_real_chief_rays(tmp_path, capsys):
    from strict_json import strict_loads

    lens = replace(Lens.load("solas-doublet"), name="tilted", image_placement=Placement(tilt_x=0.5))
    path = lens.save(tmp_path / "tilted.toml")
    assert main(["lens", "info", str(path), "--json"]) == 0
    info = strict_loads(capsys.readouterr().out)
    assert info["paraxial_axis"] == placement.metadata(lens)["paraxial_axis"] and info["distortion"] is None
    fields = [0.0, lens.field_deg, -lens.field_deg]
    for row, w in zip(info["per_wavelength"], lens.wavelengths_nm):
        aimed = local_aim.chief_rays(lens, np.array([[0.0, f] for f in fields]), w).image_xy[:, 1]
        assert row["real_chief_ray_image_height_mm"] == aimed.tolist()
        assert abs(aimed[1] + aimed[2]) > 1e-3  # the tilt makes +y and −y differ (measured: 5.3 µm)
    assert main(["lens", "info", str(path)]) == 0
    out = capsys.readouterr().out
    assert f"note: {info['paraxial_axis']}" in out and "no distortion table" in out
