"""Labels through the lens (`render.labels`): depth, normal and instance layers traced along each
pixel's chief ray line up with the rendered image, with the optics tracer's chief rays and with the
scene's geometry."""

from pathlib import Path

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics.paraxial import paraxial
from solas_mi.optics.pupil import chief_rays
from solas_mi.render.labels import instance_id, parse_labels, render_labels
from solas_mi.render.stock import render_scene
from solas_mi.render.user_scene import load

LAMBDA = 587.5618
MONO = f"mono:{LAMBDA}"
SUB = 8  # label sub-pixels per pixel side, for the labels' coverage of a pixel
# a small aperture far ahead of the stop: past 5.7 deg it blocks the chief ray while part of the beam passes
DATA = Path(__file__).parents[1] / "data"
VIGNETTING = DATA / "stiff" / "vignetting_front.toml"


def lens_named(name: str) -> Lens:
    return Lens.load(VIGNETTING if name == "vignetting-front" else name)


def patch(name: str, x0: float, x1: float, y0: float, y1: float, z: float, emit: bool = True) -> str:
    """A named rectangle [x0, x1] × [y0, y1] at depth z facing the camera (at the origin, looking along +z)."""
    body = '<emitter type="area"><rgb name="radiance" value="1"/></emitter>' if emit else '<bsdf type="diffuse"/>'
    return (
        f'<shape type="rectangle" id="{name}"><transform name="to_world"><scale x="{(x1 - x0) / 2}" '
        f'y="{(y1 - y0) / 2}"/><rotate y="1" angle="180"/><translate x="{(x0 + x1) / 2}" y="{(y0 + y1) / 2}" '
        f'z="{z}"/></transform>{body}</shape>'
    )


def scene_file(path, shapes: list[str], width: int, height: int) -> str:
    """A scene of `shapes` seen by a perspective camera (replaced by the lens camera), a box pixel filter,
    and a path integrator that sees only what glows (no noise of light transport)."""
    path.write_text(
        '<scene version="3.0.0"><integrator type="path"><integer name="max_depth" value="1"/></integrator>'
        '<sensor type="perspective"><float name="fov" value="60"/><transform name="to_world"><lookat '
        'origin="0,0,0" target="0,0,1" up="0,1,0"/></transform><film type="hdrfilm"><integer name="width" '
        f'value="{width}"/><integer name="height" value="{height}"/><rfilter type="box"/></film></sensor>'
        f"{''.join(shapes)}</scene>"
    )
    return str(path)


def at_angle(deg: float, distance: float) -> float:
    """The x (or y) on the plane z = distance seen `deg` off the axis."""
    return distance * np.tan(np.radians(deg))


def edge(profile: np.ndarray, inside: int) -> float:
    """Where a line's step from 0 (at index 0) to its level (from index `inside` on: the mean of the next
    3 pixels) lies, in pixels from the line's start: `inside` less the sum of the profile before it over
    the level (exact for box pixels of a sharp edge, and for any blur symmetric about it)."""
    level = profile[inside : inside + 3].mean()
    return inside - float(profile[:inside].sum()) / level


def edge_offsets(image: np.ndarray, cover: np.ndarray, blur: int = 0) -> list[float]:
    """Per row and column fully crossing a patch (its corners' rows and columns left out, and `blur` more
    at each end), the offsets (px) of its two edges along that line in the image from those of the
    labels' coverage; the level and the profile's start taken `blur` pixels further from the edge."""
    offsets = []
    for img, cov in ((image, cover), (image.T, cover.T)):
        lines = np.flatnonzero(cov.max(axis=1) >= 1.0)
        for r in lines[1 + blur : len(lines) - 1 - blur]:
            touched, full = np.flatnonzero(cov[r] > 0.0), np.flatnonzero(cov[r] >= 1.0)
            start, stop = max(touched[0] - 3 - blur, 0), touched[-1] + 3 + blur  # this patch alone
            assert stop < len(cov[r]) and full[-1] - full[0] >= 2 * blur + 2  # the level clear of both blurs
            for sl, inside in (
                (slice(start, None), full[0] - start + blur),
                (slice(stop, None, -1), stop - full[-1] + blur),
            ):
                offsets.append(edge(img[r][sl], inside) - edge(cov[r][sl], inside))
    return offsets


def coverage(ids: np.ndarray, shape_id: int) -> np.ndarray:
    """The fraction of each pixel's SUB × SUB label samples on the shape."""
    h, w = ids.shape[0] // SUB, ids.shape[1] // SUB
    return (ids == shape_id).reshape(h, SUB, w, SUB).mean(axis=(1, 3))


# lens, pixel pitch (um), sensor (w, h), patches: (name, field x0, x1, y0, y1 in degrees)
LENSES = {
    "nikkor-fisheye": (
        300.0,
        (96, 72),
        [
            ("centre", -8, 8, -6, 6),
            ("right", 30, 48, -10, 10),
            ("left", -70, -55, -8, 8),
            ("top", -10, 10, 35, 55),
            ("corner", -50, -35, -50, -35),
        ],
    ),
    "wide-angle-22mm": (
        360.0,
        (96, 72),
        [
            ("centre", -6, 6, -5, 5),
            ("right", 20, 32, -6, 6),
            ("left", -34, -26, -5, 5),
            ("top", -6, 6, 18, 26),
            ("corner", 24, 34, -24, -16),
        ],
    ),
    # patches in the zone where the chief ray is blocked (labels along the beam's centre) and one inside it
    "vignetting-front": (
        520.0,
        (64, 48),
        [
            ("centre", -3, 3, -2, 2),
            ("right", 6.5, 8.5, -2, 2),
            ("left", -8.5, -6.2, -1.5, 1.5),
            ("corner", 5.5, 8, 4, 6),
        ],
    ),
}


@pytest.mark.parametrize("name", LENSES)
def test_instance_edges_are_the_image_edges_across_the_field(mi, tmp_path, name):
    """Glowing patches 10 m away over the field, an unlit wall 100 m away: each patch's edges in the
    rendered image (box pixels, 64 spp) against those of its instance coverage (8×8 chief rays per
    pixel), along every row and column through the patch (`edge`): within 0.5 px everywhere; the
    depth's edges (nearer than 50 m) are the instance's."""
    pitch, (w, h), patches = LENSES[name]
    lens = lens_named(name)
    d = 10.0
    shapes = [
        patch(n, at_angle(x0, d), at_angle(x1, d), at_angle(y0, d), at_angle(y1, d), d) for n, x0, x1, y0, y1 in patches
    ] + [patch("wall", -1e4, 1e4, -1e4, 1e4, 10 * d, emit=False)]  # unlit
    image_scene = load(
        scene_file(tmp_path / "image.xml", shapes, w, h), "llvm_ad_spectral", lens, pitch_um=pitch, response=MONO
    )
    image = render_scene(image_scene, 64).image[..., 0].astype(np.float64)
    fine = load(
        scene_file(tmp_path / "fine.xml", shapes, w * SUB, h * SUB),
        "llvm_ad_spectral",
        lens,
        pitch_um=pitch / SUB,
        response=MONO,
    )
    layers, meta = render_labels(fine, ("depth", "instance"))
    near = np.where(layers["depth.Z"] < 5 * d, 1.0, 0.0)  # the patches (ranges up to 3 d) before the wall (10 d)
    worst = 0.0
    for n, *_ in patches:
        cover = coverage(layers["instance.id"], instance_id(n))
        offsets = np.abs(edge_offsets(image, cover))
        print(
            f"{name} {n}: {len(offsets)} edge crossings, max offset {offsets.max():.3f} px, mean "
            f"{offsets.mean():.3f} px"
        )
        assert len(offsets) >= 8
        worst = max(worst, offsets.max())
        depth_cover = coverage(np.where(cover.repeat(SUB, 0).repeat(SUB, 1) > 0, near, 0.0), 1.0)
        np.testing.assert_allclose(edge_offsets(cover, depth_cover), 0.0, atol=1e-6)  # the depth's edges too
    assert worst < 0.5
    assert set(meta["boxes"]) == {p[0] for p in patches} | {"wall"}


@pytest.mark.parametrize("name", ["nikkor-fisheye", "wide-angle-22mm"])
def test_label_edges_land_on_the_tracers_chief_rays(mi, tmp_path, name):
    """An independent route: strips whose edges lie at known angles, far away; along the image's middle
    row (one row of 1 um pixels at y = 0), where the instance label changes against the image height
    of the optics tracer's real chief ray at that field (its distortion)."""
    lens = Lens.load(name)
    angles = [5.0, 20.0, 35.0, 60.0, 80.0] if "fisheye" in name else [5.0, 15.0, 25.0, 35.0]
    d, pitch_um = 1e4, 1.0
    shapes = [patch(f"strip{k}", at_angle(a, d), at_angle(a + 2.0, d), -1.0, 1.0, d) for k, a in enumerate(angles)]
    width = int(
        2
        * 1.05
        * max(np.hypot(*chief_rays(lens, [[a + 2.0, 0.0]], [LAMBDA]).image_xy[0]) for a in angles)
        / (pitch_um * 1e-3)
    )
    scene = load(
        scene_file(tmp_path / "strips.xml", shapes, width, 1),
        "llvm_ad_spectral",
        lens,
        pitch_um=pitch_um,
        response=MONO,
    )
    ids = render_labels(scene, ("instance",))[0]["instance.id"][0]
    heights = np.abs(chief_rays(lens, [[a, 0.0] for a in angles], np.full(len(angles), LAMBDA)).image_xy[:, 0])
    for k, (a, expected) in enumerate(zip(angles, heights)):
        on = np.flatnonzero(ids == instance_id(f"strip{k}"))
        inner = on.max() + 1 if on.mean() < width / 2 else on.min()  # the pixel edge nearer the axis
        found = abs(inner - width / 2) * pitch_um * 1e-3  # mm from the axis
        print(f"{name} {a:g} deg: label edge {found:.4f} mm, chief ray {expected:.4f} mm")
        assert abs(found - expected) <= 0.6 * pitch_um * 1e-3, (a, found, expected)


@pytest.mark.parametrize(
    "name, pitch",
    [("wide-angle-22mm", 200.0), ("nikkor-fisheye", 200.0), ("double-gauss-50mm", 200.0), ("fast-asphere", 20.0)],
)
def test_depth_at_the_centre_is_the_distance_from_the_entrance_pupil(mi, tmp_path, name, pitch):
    """A wall at z = 5 m (from surface 1's vertex): the depth at the centre pixel (odd film, on the axis) is
    5 m plus the paraxial entrance pupil's distance behind surface 1, within 0.1 %; off the axis, the
    depth grows as the wall is met obliquely; normals face along the wall's; every pixel's id is the wall's.
    The fast asphere's film is its paraxial focus: the reversed lens has no paraxial image of it."""
    lens = Lens.load(DATA / "fast_asphere.toml") if name == "fast-asphere" else Lens.load(name)
    d = 5.0
    scene = load(
        scene_file(tmp_path / "wall.xml", [patch("wall", -50, 50, -50, 50, d, emit=False)], 33, 25),
        "llvm_ad_spectral",
        lens,
        pitch_um=pitch,
        response=MONO,
    )
    layers, meta = render_labels(scene, ("depth", "normal", "instance"))
    p = paraxial(lens)
    expected = d + (p.entrance_pupil_z_mm - lens.vertex_z[0]) * 1e-3
    depth = layers["depth.Z"]
    print(
        f"{name}: depth at the centre {depth[12, 16]:.6f}, expected {expected:.6f} "
        f"({depth[12, 16] / expected - 1.0:+.2e})"
    )
    assert abs(depth[12, 16] / expected - 1.0) < 1e-3, (depth[12, 16], expected)
    assert depth[12, 0] > depth[12, 16] and depth[0, 16] > depth[12, 16]
    assert np.all(layers["labels.valid"] == 1.0)
    np.testing.assert_allclose(layers["normal.Z"], -1.0, atol=1e-6)
    assert np.all(layers["instance.id"] == instance_id("wall"))
    assert meta["instances"] == {str(instance_id("wall")): "wall"}
    wall = dict(meta["boxes"]["wall"])
    assert len(wall.pop("box_3d")["corners_camera"]) == 8
    assert wall == {"id": instance_id("wall"), "box": [0, 0, 33, 25], "pixels": 33 * 25}


@pytest.mark.parametrize("name", ["wide-angle-22mm", "nikkor-fisheye"])
def test_3d_boxes_project_through_the_lens_onto_the_2d_boxes(mi, tmp_path, name):
    """A far patch 5..15 deg right and 3..12 deg up, seen off the axis where the lens distorts: its 3D box's
    corners (the camera frame, from the entrance pupil) projected through the lens's chief-ray mapping bound
    the pixels its instance label covers (the 2D box, end exclusive) to within a pixel; a pinhole of the lens's
    focal length would put them tens of pixels away."""
    d, pitch = 1e3, 100.0
    shapes = [patch("box", at_angle(-15.0, d), at_angle(-5.0, d), at_angle(3.0, d), at_angle(12.0, d), d)]
    scene = load(
        scene_file(tmp_path / "box.xml", shapes, 161, 121),
        "llvm_ad_spectral",
        Lens.load(name),
        pitch_um=pitch,
        response=MONO,
    )
    meta = render_labels(scene, ("instance",))[1]["boxes"]["box"]
    x0, y0, x1, y1 = meta["box"]
    box = meta["box_3d"]
    uv = np.array(box["corners_px"], dtype=np.float64)
    assert np.array(box["corners_camera"])[:, 2] == pytest.approx(
        d + (paraxial(Lens.load(name)).entrance_pupil_z_mm - Lens.load(name).vertex_z[0]) * 1e-3, rel=1e-6
    )
    print(name, meta["box"], uv.min(axis=0), uv.max(axis=0))
    assert abs(uv[:, 0].min() - (x0 - 0.5)) <= 1.0 and abs(uv[:, 0].max() - (x1 - 0.5)) <= 1.0
    assert abs(uv[:, 1].min() - (y0 - 0.5)) <= 1.0 and abs(uv[:, 1].max() - (y1 - 0.5)) <= 1.0


def test_background_and_past_the_image_circle_are_zero_and_not_valid(mi, tmp_path):
    """The fisheye's film reaches past its image circle, and nothing surrounds the patch: no label is NaN
    or inf; where no chief ray passes or nothing is met, every layer is 0 and not valid."""
    lens = Lens.load("nikkor-fisheye")
    scene = load(
        scene_file(tmp_path / "one.xml", [patch("p", -1, 1, -1, 1, 10.0)], 40, 30),
        "llvm_ad_spectral",
        lens,
        pitch_um=900.0,
        response=MONO,
    )
    layers, _meta = render_labels(scene, ("depth", "normal", "instance"))
    for layer in layers.values():
        assert np.all(np.isfinite(layer))
    valid = layers["labels.valid"] == 1.0
    assert valid[15, 20] and not valid[0, 0] and 0 < valid.sum() < 100
    for layer in layers.values():
        assert np.all(layer[~valid] == 0.0)


def test_unnamed_shapes_keep_their_ids_whatever_their_order(mi, tmp_path):
    """An unnamed shape's instance id follows its geometry, not its place in the scene's shape list (which
    differs between the LLVM and CUDA variants): the same patches listed in the other order get the same
    ids at the same pixels, and two patches get two ids."""
    unnamed = [patch("", -3, -1, -1, 1, 10.0).replace(' id=""', ""), patch("", 1, 3, -1, 1, 10.0).replace(' id=""', "")]
    lens = Lens.load("wide-angle-22mm")
    found = []
    for tag, shapes in (("ab", unnamed), ("ba", unnamed[::-1])):
        scene = load(
            scene_file(tmp_path / f"{tag}.xml", shapes, 40, 30), "llvm_ad_spectral", lens, pitch_um=400.0, response=MONO
        )
        layers, meta = render_labels(scene, ("instance",))
        found.append((layers["instance.id"], meta["instances"]))
    (ids_ab, table_ab), (ids_ba, table_ba) = found
    assert len(table_ab) == 2 and table_ab == table_ba
    np.testing.assert_array_equal(ids_ab, ids_ba)
    assert all(name.startswith("_shape_") for name in table_ab.values())


def test_label_names_are_checked():
    assert parse_labels("instance, depth") == ("depth", "instance")
    assert parse_labels(None) == ()
    with pytest.raises(SolasError, match="'colour' must be among depth, normal, instance"):
        parse_labels("depth,colour")


def test_ids_are_stable_and_never_the_background():
    assert instance_id("car") == instance_id("car") != instance_id("cars")
    assert all(0 < instance_id(f"s{k}") < 2**24 for k in range(1000))


def test_render_labels_command_writes_the_layers_beside_the_image(mi, tmp_path, capsys):
    """`solas-mi render SCENE --lens LENS --labels …`: the EXR holds the image's channels and the label
    layers, its metadata the id table and boxes, and the camera (lens, sensor, the calibration); without a lens camera, or for an image, refused in one line."""
    from solas_mi.cli import main
    from solas_mi.imageio import read_exr
    from solas_mi.render.image import render_image

    xml = scene_file(
        tmp_path / "two.xml",
        [patch("left", 0.5, 2.0, -0.5, 0.5, 5.0), patch("wall", -9, 9, -9, 9, 8.0, emit=False)],
        32,
        24,
    )
    out = tmp_path / "out.exr"
    assert (
        main(
            [
                "render",
                xml,
                "--lens",
                "wide-angle-22mm",
                "--pitch-um",
                "700",
                "--spp",
                "2",
                "--labels",
                "instance,normal,depth",
                "--calibration-model",
                "opencv-pinhole",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    data, meta = read_exr(out)
    camera = meta["camera"]  # every output says its camera: the lens, sensor, pitch, focus and the chosen model's fit
    assert (camera["lens"], camera["sensor_px"], camera["pitch_um"]) == ("wide-angle-22mm", [32, 24], 700.0)
    assert camera["focus_distance_mm"] == "inf" and camera["calibration"]["model"] == "opencv-pinhole"
    efl_px = paraxial(Lens.load("wide-angle-22mm"), camera["wavelength_nm"]).efl_mm / 0.7
    assert camera["calibration"]["parameters"]["fx"] == pytest.approx(efl_px, rel=1e-4)
    assert camera["calibration"]["max_residual_px"] < 0.1
    assert set(data) == {"R", "G", "B", "depth.Z", "normal.X", "normal.Y", "normal.Z", "instance.id", "labels.valid"}
    assert (tmp_path / "out.png").is_file()
    labels = meta["labels"]
    assert labels["kinds"] == ["depth", "normal", "instance"] and set(labels["boxes"]) == {"left", "wall"}
    x0, y0, x1, y1 = labels["boxes"]["left"]["box"]
    assert x1 <= 16 and np.all(data["instance.id"][y0:y1, x0:x1].max() == instance_id("left"))  # camera +x: image left
    assert main(["render", xml, "--labels", "depth", "--spp", "1", "-o", str(tmp_path / "no.exr")]) == 2
    assert "labels are traced through a lens_camera" in capsys.readouterr().err
    with pytest.raises(SolasError, match="no scene to label"):
        render_image(Lens.load("solas-doublet"), np.ones((4, 4)), sensor=(4, 4), spp=1, labels="depth")


@pytest.mark.parametrize("name, pitch", [("vignetting-front", 1040.0), ("nikkor-fisheye", 900.0)])
def test_labels_are_valid_wherever_the_image_has_light(mi, tmp_path, name, pitch):
    """A glowing dome all around: wherever the rendered image (64 spp) has light above 1e-3 of its peak,
    the labels are valid, also where an aperture before the stop blocks the chief ray (the vignetting
    lens past 5.7 deg: labels along the centre of the beam that passes) and in pixels at the rim of the
    fisheye's image circle whose centre sees no light but whose area does; the metadata counts them."""
    dome = (
        '<shape type="sphere" id="dome"><float name="radius" value="1000"/><boolean name="flip_normals" '
        'value="true"/><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>'
    )
    scene = load(
        scene_file(tmp_path / "dome.xml", [dome], 32, 24),
        "llvm_ad_spectral",
        lens_named(name),
        pitch_um=pitch,
        response=MONO,
    )
    image = np.abs(render_scene(scene, 64).image.astype(np.float64)).sum(axis=-1)
    layers, meta = render_labels(scene, ("depth", "instance"))
    lit, valid = image > 1e-3 * image.max(), layers["labels.valid"] == 1.0
    print(
        f"{name}: {lit.sum()} lit pixels, {valid.sum()} valid, {meta.get('beam_centre_pixels')} along the beam's "
        f"centre, {(lit & ~valid).sum()} lit but not valid"
    )
    assert not np.any(lit & ~valid)
    assert 0 < meta["beam_centre_pixels"] < valid.sum()
    assert np.all(layers["depth.Z"][valid] > 900.0) and np.all(layers["instance.id"][valid] == instance_id("dome"))
    assert np.all(layers["depth.Z"][~valid] == 0.0)


# lens, pixel pitch (um), sensor (w, h), patch distance (m), patches: (name, field x0, x1, y0, y1 in degrees)
DEFOCUSED = {
    "wide-angle-22mm": (360.0, (96, 64), 0.15, [("right", 12, 26, -9, 9), ("corner", -30, -16, 5, 20)]),
    # wholly past 5.7 deg, where the front aperture blocks the chief ray: the labels follow the beam's centre
    "vignetting-front": (520.0, (104, 48), 0.7, [("right", 6.8, 11.8, -4, 4), ("left", -11.8, -6.8, -4, 4)]),
}


@pytest.mark.parametrize("name", DEFOCUSED)
def test_a_defocused_edge_is_centred_on_the_label_edge(mi, tmp_path, name):
    """The lens focused at infinity, glowing patches near it (blurred over 1-3 px), the image divided by
    that of a glowing wall at their distance (the fall-off of the light across a blur taken out): each
    edge's place in the image, the centroid of its blur, against the label's edge, along every row and
    column through the patch: within 0.5 px off the axis, where the chief ray passes (wide angle) and where
    the front aperture blocks it (the vignetting lens: labels along the passing beam's centroid)."""
    pitch, (w, h), d, patches = DEFOCUSED[name]
    lens, blur = lens_named(name), 4

    def image(shapes, tag):
        scene = load(
            scene_file(tmp_path / f"{tag}.xml", shapes, w, h), "llvm_ad_spectral", lens, pitch_um=pitch, response=MONO
        )
        return render_scene(scene, 1024).image.astype(np.float64).sum(axis=-1)

    shapes = [
        patch(n, at_angle(x0, d), at_angle(x1, d), at_angle(y0, d), at_angle(y1, d), d) for n, x0, x1, y0, y1 in patches
    ]
    flat = image([patch("flat", -100 * d, 100 * d, -100 * d, 100 * d, d)], "flat")
    seen = image(shapes, "patches") / np.where(flat > 0.0, flat, 1.0)
    fine = load(
        scene_file(tmp_path / "fine.xml", shapes, w * SUB, h * SUB),
        "llvm_ad_spectral",
        lens,
        pitch_um=pitch / SUB,
        response=MONO,
    )
    layers, meta = render_labels(fine, ("instance",))
    assert (meta["beam_centre_pixels"] > 0) == (name == "vignetting-front")
    for n, *_ in patches:
        offsets = np.abs(edge_offsets(seen, coverage(layers["instance.id"], instance_id(n)), blur))
        print(
            f"{name} {n}: {len(offsets)} edge crossings, max offset {offsets.max():.3f} px, mean "
            f"{offsets.mean():.3f} px; {meta['beam_centre_pixels']} label pixels along the beam's centre"
        )
        assert len(offsets) >= 8 and offsets.max() < 0.5


def _placed(shape: str, ops: str) -> str:
    """`shape` (one of `patch`'s, or any shape with one `to_world`) moved further by the transform `ops`."""
    return shape.replace("</transform>", f"{ops}</transform>", 1)


def test_shapegroup_instances_take_their_own_ids(mi, tmp_path):
    """A shapegroup (a pole and a sphere) placed by two instances, one named and one unnamed, rotated:
    every pixel that meets an instance takes that instance's id (never the background's 0 with
    labels.valid 1), and each instance covers the pixels that the same two shapes placed one by one
    (the instance's transform written after their own) cover; an unnamed wall and a glowing patch keep
    their ids in both scenes; depth and normals are those of the shapes placed one by one. At most 2
    pixels of a mask may differ: an instance is intersected in its own frame, in float32."""
    pole = patch("pole", -0.25, 0.25, -2.0, 1.0, 0.0, emit=False)
    knob = (
        '<shape type="sphere" id="knob"><float name="radius" value="0.5"/><transform name="to_world">'
        '<translate y="1.5"/></transform><bsdf type="diffuse"/></shape>'
    )
    places = {"left": '<translate x="-2" z="10"/>', "": '<rotate z="1" angle="30"/><translate x="2" z="10"/>'}
    common = [
        patch("lamp", -0.5, 0.5, -2.8, -2.3, 9.0),
        patch("", -9, 9, -9, 9, 12.0, emit=False).replace(' id=""', ""),
    ]
    instanced = [f'<shape type="shapegroup" id="post">{pole}{knob}</shape>'] + [
        f'<shape type="instance"{f" id={name!r}" if name else ""}><ref id="post"/><transform name="to_world">{ops}'
        "</transform></shape>"
        for name, ops in places.items()
    ]
    flat = [
        _placed(s.replace(f'id="{part}"', f'id="{name or "right"}.{part}"'), ops)
        for name, ops in places.items()
        for s, part in ((pole, "pole"), (knob, "knob"))
    ]
    lens = Lens.load("wide-angle-22mm")
    found = []
    for tag, shapes in (("instanced", instanced + common), ("flat", flat + common)):
        scene = load(
            scene_file(tmp_path / f"{tag}.xml", shapes, 40, 30), "llvm_ad_spectral", lens, pitch_um=400.0, response=MONO
        )
        found.append(render_labels(scene, ("depth", "normal", "instance")))
    (layers, meta), (flat_layers, flat_meta) = found
    ids, flat_ids, valid = layers["instance.id"], flat_layers["instance.id"], layers["labels.valid"] == 1.0
    assert not np.any(valid & (ids == 0.0)), "pixels that meet a shape labelled as the background"
    np.testing.assert_array_equal(valid, flat_layers["labels.valid"] == 1.0)
    unnamed = [n for n in meta["instances"].values() if n.startswith("_instance_post_")]
    assert len(unnamed) == 1 and "left" in meta["boxes"], meta["instances"]
    for name in ("left", unnamed[0]):
        parts = [instance_id(f"{'left' if name == 'left' else 'right'}.{p}") for p in ("pole", "knob")]
        mine, theirs = ids == instance_id(name), np.isin(flat_ids, parts)
        print(f"{name}: {mine.sum()} pixels, placed one by one {theirs.sum()}")
        assert mine.sum() > 20 and (mine != theirs).sum() <= 2
    for name in set(meta["instances"].values()) - {"left", unnamed[0]}:  # the wall and the lamp
        assert name in flat_meta["instances"].values()
        assert ((ids == instance_id(name)) != (flat_ids == instance_id(name))).sum() <= 2
    placed = {
        instance_id(f"{side}.{p}"): instance_id(name)
        for side, name in (("left", "left"), ("right", unnamed[0]))
        for p in ("pole", "knob")
    }
    same = valid & (np.vectorize(lambda i: placed.get(int(i), int(i)))(flat_ids) == ids)
    for name in ("depth.Z", "normal.X", "normal.Y", "normal.Z"):  # an instance's points and normals, in the world
        np.testing.assert_allclose(layers[name][same], flat_layers[name][same], rtol=1e-4, atol=1e-4)


def test_scenes_mitsuba_cannot_instance_are_refused_in_one_line(mi, tmp_path, capsys):
    """A shapegroup inside a shapegroup, or holding an emitter: Mitsuba refuses to build either, and
    `render --labels` says so in one line (exit 2)."""
    from solas_mi.cli import main

    inner = '<shape type="shapegroup" id="inner"><shape type="sphere"/></shape>'
    cases = {
        "nested": inner + '<shape type="shapegroup" id="outer"><shape type="instance"><ref id="inner"/></shape>'
        '</shape><shape type="instance"><ref id="outer"/></shape>',
        "emitter": '<shape type="shapegroup" id="lamp"><shape type="sphere"><emitter type="area"/></shape>'
        '</shape><shape type="instance"><ref id="lamp"/></shape>',
    }
    for tag, shapes in cases.items():
        xml = scene_file(tmp_path / f"{tag}.xml", [shapes], 8, 6)
        assert (
            main(
                [
                    "render",
                    xml,
                    "--lens",
                    "wide-angle-22mm",
                    "--pitch-um",
                    "700",
                    "--spp",
                    "1",
                    "--labels",
                    "instance",
                    "-o",
                    str(tmp_path / f"{tag}.exr"),
                ]
            )
            == 2
        )
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and ("Nested instancing" in err or "Instancing of emitters" in err), err


def test_meshes_of_one_material_keep_their_own_ids(mi, tmp_path):
    """Two named rectangles and an unnamed wall sharing one diffuse material (which Mitsuba's parser by
    default merges into one unnamed mesh): each keeps its own id over the pixels its rectangle covers,
    as the same rectangles glowing (emitters, never merged) cover them."""
    shapes = {"a": (-3.0, -1.0), "b": (1.0, 3.0)}
    lens = Lens.load("wide-angle-22mm")
    found = []
    for emit in (False, True):
        items = [patch(n, x0, x1, -1, 1, 10.0, emit=emit) for n, (x0, x1) in shapes.items()]
        items.append(patch("", -9, 9, -9, 9, 12.0, emit=emit).replace(' id=""', ""))
        scene = load(
            scene_file(tmp_path / f"{emit}.xml", items, 40, 30), "llvm_ad_spectral", lens, pitch_um=400.0, response=MONO
        )
        found.append(render_labels(scene, ("instance",)))
    (diffuse, meta), (glowing, glowing_meta) = found
    assert meta["instances"] == glowing_meta["instances"] and len(meta["instances"]) == 3, meta["instances"]
    np.testing.assert_array_equal(diffuse["instance.id"], glowing["instance.id"])
    for name in shapes:
        assert (diffuse["instance.id"] == instance_id(name)).sum() > 20


def test_the_render_memory_estimate_counts_the_label_layers(mi, tmp_path, monkeypatch, capsys):
    """`render --labels` said 1.5 GB and peaked at 3.0 GB: the estimate left the labels out. It now adds
    the label rays' trace (measured ~100 B a pixel) and each channel the layers hold: it grows with the
    layers as their arrays do (at least their own bytes, more for each channel), and a render that fits
    without labels is refused with them where the memory does not hold both."""
    from solas_mi import budget
    from solas_mi.cli import main
    from solas_mi.render.commands import check_render
    from solas_mi.render.labels import memory_bytes

    w, h = 40, 30
    scene = load(
        scene_file(tmp_path / "wall.xml", [patch("wall", -9, 9, -9, 9, 8.0)], w, h),
        "llvm_ad_spectral",
        Lens.load("wide-angle-22mm"),
        pitch_um=700.0,
        response=MONO,
    )
    estimates, arrays = [], []
    for kinds in ("", "depth", "depth,instance", "depth,normal,instance"):
        layers = render_labels(scene, kinds)[0] if kinds else {}
        estimates.append(memory_bytes(w * h, kinds))
        arrays.append(sum(a.nbytes for a in layers.values()))
        assert estimates[-1] >= arrays[-1]
    assert estimates[0] == 0 and np.all(np.diff(estimates) > 0) and np.all(np.diff(estimates) >= np.diff(arrays))
    size = 2000  # a film of 2000 x 1500: the base estimate and the labels' both about 400 MB
    monkeypatch.setattr(budget, "available_memory", lambda: 600e6)
    check_render(size, 1500, 1, False)
    with pytest.raises(SolasError, match=r"render 2000x1500 with labels depth,normal,instance needs about"):
        check_render(size, 1500, 1, False, "instance,normal,depth")
    xml = scene_file(tmp_path / "big.xml", [patch("wall", -9, 9, -9, 9, 8.0)], size, 1500)
    assert (
        main(
            [
                "render",
                xml,
                "--lens",
                "wide-angle-22mm",
                "--pitch-um",
                "30",
                "--spp",
                "1",
                "--labels",
                "depth",
                "-o",
                str(tmp_path / "big.exr"),
            ]
        )
        == 2
    )
    assert "with labels depth needs about" in capsys.readouterr().err
