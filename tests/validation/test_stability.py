"""Stiff and extreme cases (`validation.stability`, `solas-mi check-stability`): the shipped lenses pass
every case, and each class has a lens of our own (tests/data/stiff/) that failed before its fix."""
from pathlib import Path

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.cli import main
from solas_mi.optics.pupil import pupil_function
from solas_mi.psf.geometric import geometric
from solas_mi.validation import stability
from solas_mi.validation.stability import check_stability

STIFF = Path(__file__).parents[1] / "data" / "stiff"


@pytest.mark.parametrize("name", ["solas-doublet", "cooke-triplet", *sorted(p.name for p in STIFF.glob("*.toml"))])
def test_every_case_passes(name):
    lens = Lens.load(STIFF / name if name.endswith(".toml") else name)
    cases = check_stability(lens)
    assert len(cases) >= 20
    failed = [c.to_dict() for c in cases if not c.passed]
    assert not failed, failed


def test_a_pupil_cut_by_total_internal_reflection_is_built_from_the_rays_that_pass():
    """The steep singlet's rim rays meet the flat rear face beyond the critical angle: the pupil was
    refused ("no real ray reaches the stop's rim ... not usable"); now its edge is found inside the
    rim, and wave and ray optics agree on the light that passes."""
    lens = Lens.load(STIFF / "steep_singlet.toml")
    pf = pupil_function(lens, [[0.0, 0.0]], [587.5618], 256)
    rays = geometric(lens, np.array([[0.0, 0.0]]), np.array([587.5618]), 2.0, 32, rays=800)[2]
    assert 0.5 < rays[0] < 0.95  # TIR really cuts the pupil
    assert pf.transmission[0] == pytest.approx(rays[0], rel=0.01)


def test_a_batch_of_fields_aims_each_field_as_alone():
    """Aiming stops per ray: a stiff field in the batch no longer stops the others' iteration early
    (the steep singlet's on-axis transmission was 0.76 in a batch, 0.82 alone)."""
    lens = Lens.load(STIFF / "steep_singlet.toml")
    fields = np.array([[0.0, 0.0], [0.0, 7.0], [0.0, 10.0]])
    batch = pupil_function(lens, fields, [587.5618] * 3, 64).transmission
    alone = [pupil_function(lens, fields[i:i + 1], [587.5618], 64).transmission[0] for i in range(3)]
    assert batch == pytest.approx(alone, rel=1e-4)


def test_the_exit_pupil_bound_holds_a_ball_lens():
    """A ball lens's rear rim bends away from the film (negative sag larger than the back distance):
    the search reach became 1e9 mm and nearly every ray fell outside the bound; a pupil that is not
    convex kept only part of its rim."""
    case = stability._exit_pupil(Lens.load(STIFF / "ball_lens.toml"), 587.5618)
    assert case.passed, case.observed


def test_the_command_prints_the_table_and_fails_on_a_failed_case(capsys, monkeypatch):
    assert main(["check-stability", "solas-doublet"]) == 0
    out = capsys.readouterr().out
    assert "22 of 22 cases pass" in out and "| render's exit-pupil bound |" in out
    monkeypatch.setattr(stability, "_centred", lambda *a: stability.Case("centring", "x", "y", False))
    assert main(["check-stability", "solas-doublet", "--json"]) == 1
    out, err = capsys.readouterr()
    assert '"passed": false' in out and "1 case(s) failed: centring" in err
