"""`solas-mi lens info` (optics.commands)."""
import pytest

# DESIGN.md: facts about the SOLAS doublet that independent tools agree on.


def test_cli_lens_info_json(capsys):
    import json

    from solas_mi.cli import main

    assert main(["lens", "info", "solas-doublet", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    rows = {r["wavelength_nm"]: r for r in info["per_wavelength"]}
    assert rows[531.0]["efl_mm"] == pytest.approx(99.9468, abs=1e-3)
    assert rows[531.0]["real_chief_ray_image_height_mm"][1] == pytest.approx(3.4745, abs=1e-3)
