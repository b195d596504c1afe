"""The lens as Mitsuba meshes holds bare glass and a round stop: a lens stating a coating or an iris is
refused by name there (`render.scene`), never rendered as something else."""

import pytest

from solas_mi import Lens
from solas_mi.errors import SolasError


def test_the_mesh_scene_refuses_an_iris_and_a_coating_by_name(doublet, doublet_spec):
    """The lens as Mitsuba meshes has bare glass and a round stop: a lens that states either is refused,
    naming the surface and the tracer ways, never rendered as something else."""
    from solas_mi.render.scene import lens_parts

    doublet_spec["surface"][doublet.stop_index]["blades"] = 6
    doublet_spec["surface"][0]["coating"] = "quarter_wave"
    with pytest.raises(SolasError, match="surface 1's coating, surface 4's iris \\(blades\\) has no Mitsuba geometry"):
        lens_parts(Lens.from_dict(doublet_spec))
    assert lens_parts(doublet)  # the bare, round lens builds as before


def test_the_render_psf_method_takes_a_coated_lens_as_its_bare_glass(doublet_spec):
    """The "render" PSF method's glass has no Fresnel losses: a coating changes nothing there, so a coated
    lens is built (its iris still refused)."""
    from solas_mi.psf.methods import psf

    doublet_spec["surface"][0]["coating"] = "quarter_wave"
    coated, bare = Lens.from_dict(doublet_spec), Lens.load("solas-doublet")
    a, b = (
        psf(lens, (0.0, 1.0), 531.0, size=16, pitch_um=4.0, method="render", rays=32).data for lens in (coated, bare)
    )
    assert (a == b).all()
