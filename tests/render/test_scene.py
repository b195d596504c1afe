"""The lens as Mitsuba geometry (`render.scene`): cap meshes and the parts of a lens."""

from pathlib import Path

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.render.scene import cap_mesh, lens_parts


def test_cap_mesh_lies_on_the_sphere_and_faces_the_object():
    v, n, f = cap_mesh(-30.716, 6.0, 15.0, 32)
    centre = np.array([0.0, 0.0, 6.0 - 30.716])
    assert np.allclose(np.linalg.norm(v - centre, axis=1), 30.716, atol=1e-9)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0) and np.all(n[:, 2] < 0)
    geo = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    assert np.all(geo[:, 2] < 0)  # winding agrees with the normals
    # the flat triangles sit inside the sphere by about (edge length)² / 8R, no more
    edge = np.linalg.norm(v[f[:, 1]] - v[f[:, 2]], axis=1).max()
    depth = 30.716 - np.linalg.norm(v[f].mean(axis=1) - centre, axis=1)
    assert 0 < depth.max() < 1.5 * edge**2 / (8 * 30.716)


def test_parts_of_the_doublet(doublet):
    names = [p.name for p in lens_parts(doublet, 16)]
    # three refracting caps (the stop refracts nothing), an absorbing ring per aperture, the barrel
    assert names == ["surface1", "aperture1", "surface2", "aperture2", "surface3", "aperture3", "aperture4", "barrel"]
    glasses = [(p.ext_glass, p.int_glass) for p in lens_parts(doublet, 16) if p.int_glass]
    assert glasses == [("AIR", "BK7"), ("BK7", "SCHOTT:F2"), ("SCHOTT:F2", "AIR")]


def test_bad_ring_count(doublet):
    with pytest.raises(SolasError, match="rings"):
        lens_parts(doublet, 1)


def test_surfaces_closer_than_the_ray_continuation_are_refused(doublet_spec):
    """A 5e-5 mm air gap between two refracting surfaces: a ray continued 1e-4 mm past the first would
    skip the second, so the mesh scene refuses the lens with the surfaces and the minimum named (the
    tracer takes it)."""
    from solas_mi import Lens

    spec = dict(doublet_spec)
    spec["surface"] = [dict(s) for s in doublet_spec["surface"]]
    spec["surface"][1]["material"] = "AIR"
    spec["surface"][1]["thickness"] = 5e-5
    spec["surface"].insert(2, dict(spec["surface"][1], thickness=3.0, material="SCHOTT:F2", label="thin"))
    lens = Lens.from_dict(spec)
    with pytest.raises(SolasError, match=r"surfaces 2 and 3 .* are 5e-05 mm apart .* at least 0.001 mm apart"):
        lens_parts(lens)


def test_a_lens_changed_in_memory_is_the_lens_the_scene_loads(tmp_path, doublet):
    """The sensor loads its lens from a file: an unchanged lens names its own file; a lens changed in
    memory (here refocused) is written beside the scene, never replaced by its file's lens."""
    import xml.etree.ElementTree as ET

    from solas_mi import Lens
    from solas_mi.optics.focus import focused
    from solas_mi.render.scene import lens_file, write_scene

    assert lens_file(doublet) == Path(doublet.source)
    near = focused(doublet, 2000.0)
    assert near.source == doublet.source and near.hash != doublet.hash
    with pytest.raises(SolasError, match="differs from its file"):
        lens_file(near)
    for lens, folder in ((doublet, tmp_path / "same"), (near, tmp_path / "near")):
        xml = write_scene(lens, folder, "white.exr")
        named = [e.get("value") for e in ET.parse(xml).iter("string") if e.get("name") == "lens"]
        assert len(named) == 1
        loaded = Lens.load(folder / named[0])
        assert loaded.hash == lens.hash and loaded.image_z == pytest.approx(lens.image_z, abs=1e-12)
    assert (tmp_path / "same" / Path(doublet.source).name).read_text() == Path(doublet.source).read_text()


def test_a_user_scene_names_the_lens_changed_in_memory(tmp_path, doublet):
    from solas_mi.optics.focus import focused
    from solas_mi.render.user_scene import load

    scene = tmp_path / "scene.xml"
    scene.write_text(
        '<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="4"/>'
        '<film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/>'
        "</film></sensor></scene>"
    )
    near = focused(doublet, 2000.0)
    held = load(scene, "llvm_ad_spectral", near).sensors()[0].lens
    assert held.hash == near.hash
    assert held.hash != doublet.hash


def test_the_lens_file_is_parsed_once_per_content(tmp_path, doublet, monkeypatch):
    """A render's caller has loaded its lens: checking that the lens still is its file's parses that
    file once, not at every render, and again as soon as the file changes (never a stale answer)."""
    import shutil

    from solas_mi import Lens
    from solas_mi.render.scene import lens_file

    source = tmp_path / "doublet.toml"
    shutil.copyfile(doublet.source, source)
    lens = Lens.load(source)
    parsed = []
    load = Lens.load.__func__
    monkeypatch.setattr(Lens, "load", classmethod(lambda cls, path: parsed.append(path) or load(cls, path)))
    assert [lens_file(lens, tmp_path / "a"), lens_file(lens, tmp_path / "b")] == [source, source]
    assert parsed == [source]
    text = source.read_text()
    source.write_text(text + "\n# edited\n")
    assert lens_file(lens, tmp_path / "c") == source and len(parsed) == 2  # same lens, new content: parsed again
    assert "thickness = 6.0" in text
    source.write_text(text.replace("thickness = 6.0", "thickness = 7.0", 1))  # same size, at once
    assert lens_file(lens, tmp_path / "d").parent == tmp_path / "d"  # the file no longer holds this lens


def test_cap_mesh_of_a_qbfs_surface_lies_on_its_sag():
    """A Forbes Qbfs surface becomes a mesh on its own sag (not the base conic's), normals from its slope."""
    from solas_mi.optics.sag import sag

    qbfs, rho = (0.05, -0.02, 0.01), 9.0
    v, n, _ = cap_mesh(30.0, 2.0, 9.0, 16, -0.7, (), qbfs, rho)
    r2 = v[:, 0] ** 2 + v[:, 1] ** 2
    assert np.abs(v[:, 2] - 2.0 - sag(r2, 1 / 30.0, -0.7, qbfs=qbfs, norm_radius=rho)).max() < 1e-14
    assert np.abs(v[:, 2] - 2.0 - sag(r2, 1 / 30.0, -0.7)).max() > 1e-3  # the Qbfs terms move it
    h = 1e-5
    r = np.sqrt(r2[1:])
    dz = (
        sag((r + h) ** 2, 1 / 30.0, -0.7, qbfs=qbfs, norm_radius=rho)
        - sag((r - h) ** 2, 1 / 30.0, -0.7, qbfs=qbfs, norm_radius=rho)
    ) / (2 * h)
    assert np.abs(-n[1:, 2] * dz - np.hypot(n[1:, 0], n[1:, 1])).max() < 1e-7  # |n_r| / |n_z| = dz/dr


@pytest.mark.parametrize("distance", [1e5, 1e12])
def test_a_lens_farther_than_float32_holds_is_refused_by_the_mesh_scene(doublet, capsys, distance, tmp_path):
    """The doublet's image plane moved 1e5 and 1e12 mm behind the stop: render-image's float32 geometry
    rendered its film in the wrong colours (1e7 mm) and black (1e12 mm); float32 holds a point to 1 µm
    only within 2^24 µm of the origin, so the mesh scene refuses it naming the reach and the tracers that
    take it; the image plane 39.496 mm away builds."""
    from dataclasses import replace

    from solas_mi.cli import main
    from solas_mi.render.scene import FLOAT32_REACH_MM

    assert pytest.approx(2**24 * 1e-3) == FLOAT32_REACH_MM
    far = replace(doublet, surfaces=(*doublet.surfaces[:-1], replace(doublet.surfaces[-1], thickness=distance)))
    with pytest.raises(
        SolasError,
        match=r"reaches .* mm from surface 1 .* float32 geometry holds a point to 1 µm "
        r"within 16777.2 mm only; trace it instead",
    ):
        lens_parts(far)
    assert lens_parts(doublet)
    path = far.save(tmp_path / "far.toml")
    assert (
        main(
            [
                "render-image",
                str(path),
                str(Path(__file__).parents[2] / "scenes" / "images" / "rocket.png"),
                "--sensor",
                "8x6",
                "--spp",
                "1",
                "-o",
                str(tmp_path / "far.exr"),
            ]
        )
        == 2
    )
    assert "float32 geometry" in capsys.readouterr().err and not (tmp_path / "far.exr").exists()


def test_the_lens_as_built_is_refused_by_name():
    """A toroid or a coordinate break has no cap mesh yet: refused naming the surface, not built symmetric."""
    from solas_mi import Lens

    rows = [
        {"radius": 0.0, "thickness": 5.0, "diameter": 10.0, "stop": True},
        {"radius": 30.0, "thickness": 3.0, "diameter": 10.0, "material": "N-BK7"},
        {"radius": 0.0, "thickness": 40.0, "diameter": 10.0},
    ]
    toroid = Lens.from_dict(
        {"name": "t", "surface": [rows[0], {**rows[1], "kind": "toroid", "radius_rotation": 20.0}, rows[2]]}
    )
    with pytest.raises(SolasError, match=r"surface 2 \(surface 2\) is a toroid, which the mesh scene"):
        lens_parts(toroid)
    tilted = Lens.from_dict({"name": "t", "surface": [rows[0], {**rows[1], "tilt_x": 1.0}, rows[2]]})
    with pytest.raises(SolasError, match="decentred or tilted"):
        lens_parts(tilted)
