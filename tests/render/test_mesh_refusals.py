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
