"""The render stage's commands (`render.commands`): `scene`, `render`, `render-image`."""
from solas_mi.cli import main
from solas_mi.imageio import read_exr


def test_scene_and_render_commands(tmp_path):
    """`solas-mi scene` writes an editable scene; `solas-mi render` renders it with overrides."""
    scene_dir = tmp_path / "scene"
    assert main(["scene", "solas-doublet", "-o", str(scene_dir), "--sensor", "16x12", "--rings", "16"]) == 0
    xml = scene_dir / "scene.xml"
    assert (scene_dir / "meshes" / "surface1.ply").is_file() and (scene_dir / "rocket.png").is_file()
    out = tmp_path / "r.exr"
    assert main(["render", str(xml), "-o", str(out), "--spp", "3", "--set", "response=lines",
                 "--variant", "llvm_ad_spectral"]) == 0
    channels, meta = read_exr(out)
    assert sorted(channels) == ["B", "G", "R"] and channels["R"].shape == (12, 16)
    assert meta["spp"] == 3 and meta["response"].startswith("lines") and out.with_suffix(".png").is_file()
    assert main(["render", str(xml), "-o", str(tmp_path / "bad.exr"), "--set", "image=missing.png"]) == 2
    assert not (tmp_path / "bad.exr").exists()
    assert main(["render-image", "solas-doublet", str(tmp_path / "nope.png"), "-o", str(tmp_path / "x.exr")]) == 2
