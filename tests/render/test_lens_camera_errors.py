"""`render SCENE --lens`: a scene camera whose numbers the lens camera cannot read is one line, exit 2."""

import pytest

from solas_mi.cli import main

SCENE = """<scene version="3.0.0">
    <sensor type="perspective">
        {field}
        <transform name="to_world"><lookat origin="0, 0, -5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="{height}"/></film>
    </sensor>
    <shape type="sphere"/>
    <emitter type="constant"/>
</scene>"""
FOV = '<float name="fov" value="4"/>'


@pytest.mark.parametrize(
    "field, width, height",
    [
        (FOV, 0, 0),
        ('<float name="fov" value="abc"/>', 24, 16),
        ('<string name="focal_length" value="abcmm"/>', 24, 16),
        (FOV, "abc", 16),
        (FOV, "$nodef", 16),
    ],
)
def test_a_camera_the_lens_camera_cannot_read_is_one_line(tmp_path, capsys, field, width, height):
    scene = tmp_path / "s.xml"
    scene.write_text(SCENE.format(field=field, width=width, height=height))
    assert main(["render", str(scene), "--lens", "solas-doublet", "--spp", "1", "-o", str(tmp_path / "o.exr")]) == 2
    err = capsys.readouterr().err
    assert "s.xml" in err and err.count("\n") == 1, err
    assert not list(tmp_path.glob("o.*"))
