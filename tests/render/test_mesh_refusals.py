"""The lens as Mitsuba meshes holds a round stop: a lens stating an iris is refused by name there
(`render.scene`), never rendered as something else; a coating is built (`coated_dielectric`)."""

import pytest

from solas_mi import Lens
from solas_mi.errors import SolasError


def test_the_mesh_scene_refuses_an_iris_by_name_and_builds_a_coating(doublet, doublet_spec):
    """The lens as Mitsuba meshes has a round stop: a lens that states an iris is refused, naming the surface
    and the tracer ways, never rendered as something else; its coating is built on its cap."""
    from solas_mi.render.scene import lens_parts

    doublet_spec["surface"][0]["coating"] = "quarter_wave"
    coated = Lens.from_dict(doublet_spec)
    assert [p.coating for p in lens_parts(coated) if p.int_glass] == [coated.surfaces[0].coating, None, None]
    doublet_spec["surface"][doublet.stop_index]["blades"] = 6
    with pytest.raises(SolasError, match="surface 4's iris \\(blades\\) has no Mitsuba geometry"):
        lens_parts(Lens.from_dict(doublet_spec))
    assert lens_parts(doublet)  # the bare, round lens builds as before


def test_the_render_psf_method_takes_a_coated_lens_as_its_bare_glass(doublet_spec):
    """The "render" PSF method's glass has no Fresnel losses (`fresnel` "off"): a coating changes nothing
    there."""
    from solas_mi.psf.methods import psf

    doublet_spec["surface"][0]["coating"] = "quarter_wave"
    coated, bare = Lens.from_dict(doublet_spec), Lens.load("solas-doublet")
    a, b = (
        psf(lens, (0.0, 1.0), 531.0, size=16, pitch_um=4.0, method="render", rays=32).data for lens in (coated, bare)
    )
    assert (a == b).all()
