"""A frame's labels through `degrade` (`convolution.labels`, `convolution.mapping`): warped by the mapping
the image went through, checked against the degraded image itself (each object's light), the tracer's
chief rays, and the labels' own rules (no id that was not in the input, depth not blended across an edge,
flow the motion of the warped objects)."""

import json
import math

import numpy as np
import pytest
from scipy import ndimage

from solas_mi import Lens, SolasError
from solas_mi.convolution.labels import label_outputs, read_labels, warp_labels
from solas_mi.convolution.mapping import blend, mapping_for, psf_centroids
from solas_mi.convolution.methods import METHODS, degrade
from solas_mi.optics.frame import FrameCamera
from solas_mi.psf.grid import psf_grid
from solas_mi.psf.spec import GridSpec

GRID = dict(grid=(11, 9), size=41, method="geometric", rays=64, field_sampling="edges")
W, H, R = 320, 216, 9  # the frame, the discs' radius (px)


@pytest.fixture(scope="module")
def wide():
    """wide-angle-22mm over ±40° x ±29° (a 3:2 frame's field: 4.5 px of distortion at 640 px wide), at its
    primary wavelength."""
    lens = Lens.load("wide-angle-22mm")
    return psf_grid(
        lens, GridSpec(**GRID, wavelengths_nm=(lens.primary_wavelength,), field_range_deg=(40.0, 29.0), pitch_um=8.0)
    )


@pytest.fixture(scope="module")
def fisheye():
    """nikkor-fisheye over ±58° x ±48°, and a Kannala–Brandt frame reaching that far."""
    lens = Lens.load("nikkor-fisheye")
    grid = psf_grid(
        lens, GridSpec(**GRID, wavelengths_nm=(lens.primary_wavelength,), field_range_deg=(58.0, 48.0), pitch_um=10.0)
    )
    return grid, FrameCamera(
        "kannala-brandt", intrinsics=(180.0, 180.0, W / 2 - 0.5, H / 2 - 0.5), coefficients=(-0.02, 0.003, 0.0, 0.0)
    )


def discs(width=W, height=H, radius=R, shift=(0.0, 0.0)):
    """A grid of discs (ids 1, 2, ...; spaced 4 radii) on 0, moved by `shift` (columns, rows) pixels."""
    rows, cols = np.mgrid[:height, :width]
    ids = np.zeros((height, width))
    step = 4 * radius
    for k, (cy, cx) in enumerate(
        (
            (y, x)
            for y in np.arange(step / 2 + 2, height - step / 2, step)
            for x in np.arange(step / 2 + 2, width - step / 2, step)
        ),
        start=1,
    ):
        ids[(rows - cy - shift[1]) ** 2 + (cols - cx - shift[0]) ** 2 <= radius**2] = k
    return ids


def centroid(weights: np.ndarray) -> np.ndarray:
    rows, cols = np.indices(weights.shape)
    return np.array([(weights * cols).sum(), (weights * rows).sum()]) / weights.sum()


def blob_errors(ids, warped, image, reach) -> tuple[list, list]:
    """Per disc: the distance of its warped label's centroid, and of its input's, from its light's centroid in
    the degraded image (within `reach` px of the label)."""
    after, before = [], []
    for k in np.unique(ids)[1:]:
        light = image * ndimage.binary_dilation(warped == k, iterations=reach)
        after.append(np.hypot(*(centroid(warped == k) - centroid(light))))
        before.append(np.hypot(*(centroid(ids == k) - centroid(light))))
    return after, before


def warp(grid, ids_or_labels, frame=None, method="interp", boundary="edge", size=(H, W), depth=None):
    labels = ids_or_labels if isinstance(ids_or_labels, dict) else {"instance": (ids_or_labels[..., None], "ids")}
    return warp_labels(labels, mapping_for(grid, size[1], size[0], frame, method, depth), boundary)


@pytest.mark.parametrize("method", list(METHODS))
def test_warped_ids_sit_on_the_degraded_discs_through_the_wide_angle(wide, method):
    """The acceptance: a grid of discs with ids on a pinhole frame through the wide angle; each warped id's
    centroid is its disc's light centroid in the degraded frame within 0.2 px (before the warp: up to a
    pixel off), and no id appears that was not in the input."""
    ids = discs()
    meta = {}
    image = degrade((ids > 0).astype(float), wide, method, meta=meta)
    layers, _, about = warp(wide, ids, method=method)
    warped = layers["instance.id"]
    after, before = blob_errors(ids, warped, image, meta["kernel_size_px"] // 2 + 1)
    print(method, f"max {max(after):.3f} px, mean {np.mean(after):.3f} px; unwarped max {max(before):.3f} px")
    assert max(after) < 0.2 and max(before) > 0.8
    assert set(np.unique(warped)) <= set(np.unique(ids)) and warped.dtype == np.float32
    assert about["max_chief_ray_offset_px"] == pytest.approx(meta["max_chief_ray_offset_px"])


def test_what_is_left_at_finer_pixels_is_the_lenss_own_coma(wide):
    """At 480x324 the light of a point lands up to 0.27 px from its chief ray (the PSF's first moment at the
    field's edge): the labels follow the chief ray, so that is what separates them from the light; taken
    out, the discs sit within 0.2 px again."""
    w, h = 480, 324
    ids = discs(w, h, 10)
    meta = {}
    image = degrade((ids > 0).astype(float), wide, meta=meta)
    layers, _, about = warp(wide, ids, size=(h, w))
    warped = layers["instance.id"]
    lay = mapping_for(wide, w, h).layouts[0]
    rows, cols = np.indices(ids.shape)
    errors = []
    for k in np.unique(ids)[1:]:
        coma = blend(lay.col_knots, lay.row_knots, psf_centroids(wide, lay, 0), cols[ids == k], rows[ids == k])
        light = image * ndimage.binary_dilation(warped == k, iterations=meta["kernel_size_px"] // 2 + 1)
        errors.append(np.hypot(*(centroid(warped == k) + coma.mean(axis=0) - centroid(light))))
    assert 0.2 < about["max_psf_centroid_px"] < 0.35 and max(errors) < 0.2


@pytest.mark.parametrize("shift", [(0.3, -0.4), (0.5, 0.5), (-0.8, 0.1)])
def test_a_sub_pixel_shift_moves_the_ids_by_as_much(synthetic_grid, shift):
    """A lens that shifts the whole image by a fraction of a pixel: each disc's ids move by that fraction
    within 0.1 px (rounding the source points would move them by whole pixels: 0.3 px → 0), and a point
    that lands on a pixel centre keeps it (no shift, no dither)."""
    pixel = synthetic_grid.pixel_um(W)
    grid = synthetic_grid(
        (1, 4, 4),
        pitch_um=pixel / 4,
        size=9,
        sigma_um=pixel / 4,
        offsets_um=np.broadcast_to(np.array([shift[0], -shift[1]]) * pixel, (1, 4, 4, 2)),
    )
    ids = discs()
    layers, _, _ = warp(grid, ids)
    moved = [centroid(layers["instance.id"] == k) - centroid(ids == k) for k in np.unique(ids)[1:]]
    assert np.abs(np.array(moved) - shift).max() < 0.1
    still = synthetic_grid((1, 4, 4), pitch_um=pixel / 4, size=9, sigma_um=pixel / 4)
    assert np.array_equal(warp(still, ids)[0]["instance.id"], ids)


def test_warped_ids_sit_on_the_degraded_discs_in_a_fisheye_frame(fisheye):
    """The acceptance in a Kannala–Brandt frame through nikkor-fisheye: the frame's calibration places every
    direction (the reference wavelength's chief ray is the frame's own point), so the ids stay where they are
    and the discs' light around them, within 0.2 px (what is left is the lens's coma in the frame's pixels)."""
    grid, frame = fisheye
    ids = discs()
    meta = {}
    image = degrade((ids > 0).astype(float), grid, frame=frame, meta=meta)
    layers, _, about = warp(grid, ids, frame)
    assert np.array_equal(layers["instance.id"], ids) and about["max_chief_ray_offset_px"] == 0.0
    after, _ = blob_errors(ids, layers["instance.id"], image, meta["kernel_size_px"] // 2 + 1)
    assert max(after) < 0.2


def test_depth_is_kept_within_a_surface_and_never_blended_across_an_edge(wide):
    """A depth ramp (5 to 13 m) with discs at 3 m: where the tracer's chief ray of a node's field lands, the
    warped depth is the ramp's at that field's ideal pixel (a linear ramp is interpolated exactly); no value
    lies between a disc and the ramp behind it; the sky's inf is written 0."""
    rows, cols = np.indices((H, W)).astype(float)
    ramp = 5.0 + 0.02 * cols + 0.01 * rows
    ids = discs()
    depth = np.where(ids > 0, 3.0, ramp)
    depth[:, :4] = np.inf
    layers, _, about = warp(wide, {"depth": (depth[..., None], "depth")})
    warped = layers["depth.Z"]
    assert about["kinds"]["depth"]["rule"] == "surface"
    assert not ((warped > 3.0) & (warped < 5.0)).any() and (warped == 3.0).sum() > 0.9 * (ids > 0).sum()
    assert (warped[:, :2] == 0).all() and np.isfinite(warped).all()
    lens = Lens.load("wide-angle-22mm")
    camera = mapping_for(wide, W, H).layouts[0].camera
    from solas_mi.optics.pupil import chief_rays

    fields = wide.fields_deg[2:-2, 2:-2].reshape(-1, 2)
    xy = chief_rays(lens, fields, np.full(len(fields), lens.primary_wavelength)).image_xy
    lands = np.stack([camera.centre[0] + xy[:, 0] / camera.pitch_mm, camera.centre[1] - xy[:, 1] / camera.pitch_mm], 1)
    ideal = camera.ideal_pixel(fields)
    for (c, r), (ic, ir) in zip(lands, ideal):
        q = np.rint([c, r]).astype(
            int
        )  # the output pixel nearest the chief ray; its source lies as far from the ideal pixel
        if ids[int(round(ir)), int(round(ic))] == 0 and np.isfinite(depth[int(round(ir)), int(round(ic))]):
            want = 5.0 + 0.02 * (ic + q[0] - c) + 0.01 * (ir + q[1] - r)
            assert warped[q[1], q[0]] == pytest.approx(want, abs=2e-3)


def test_optical_flow_is_the_motion_of_the_warped_objects(wide):
    """Discs moving by (6, -4) px to the next frame (flow given inside them): the warped flow over each warped
    disc is how far its warped label moved between the two warped frames, within 0.2 px; where nothing
    moves it stays 0."""
    ids, moved = discs(), discs(shift=(6.0, -4.0))
    flow = np.zeros((H, W, 2))
    flow[ids > 0] = (6.0, -4.0)
    layers, _, about = warp(wide, {"instance": (ids[..., None], "a"), "flow": (flow, "f")})
    following, _, _ = warp(wide, moved)
    errors = []
    for k in np.unique(ids)[1:]:
        mine = layers["instance.id"] == k
        motion = centroid(following["instance.id"] == k) - centroid(mine)
        errors.append(np.hypot(layers["flow.X"][mine].mean() - motion[0], layers["flow.Y"][mine].mean() - motion[1]))
    assert max(errors) < 0.2 and about["kinds"]["flow"]["layers"] == ["flow.X", "flow.Y"]
    assert (layers["flow.X"][layers["instance.id"] == 0] == 0).all()
    assert np.abs(layers["flow.X"][layers["instance.id"] > 0] - 6.0).max() > 0.01  # the lens changes the motion


def test_normals_and_masks_are_values_of_the_input(wide):
    ids = discs()
    angle = np.radians(7.0 * ids)
    normals = np.stack([np.sin(angle), np.zeros_like(angle), np.cos(angle)], axis=-1)
    mask = (ids % 2 == 1).astype(float)[..., None] * 255
    layers, _, _ = warp(wide, {"normal": (normals, "n"), "mask": (mask, "m")})
    got = np.stack([layers[f"normal.{a}"] for a in "XYZ"], axis=-1).reshape(-1, 3)
    assert {tuple(v) for v in np.unique(got, axis=0)} <= {
        tuple(v) for v in np.unique(normals.astype(np.float32).reshape(-1, 3), axis=0)
    }
    assert np.allclose(np.linalg.norm(got, axis=-1), 1.0, atol=1e-6)
    assert set(np.unique(layers["mask.Y"])) == {0.0, 255.0}


def test_boxes_and_keypoints_move_with_the_ids(wide):
    """COCO boxes of the discs and a keypoint at each centre: moved, each box holds its warped disc's pixels
    and hugs them, each keypoint its warped disc's centroid within 0.2 px; a box wholly outside the
    frame is dropped, a keypoint moved outside marked not labelled."""
    ids = discs()
    rows, cols = np.indices(ids.shape)
    annotations = []
    for k in np.unique(ids)[1:]:
        r, c = rows[ids == k], cols[ids == k]
        annotations.append(
            {
                "id": int(k),
                "bbox": [int(c.min()), int(r.min()), int(np.ptp(c)) + 1, int(np.ptp(r)) + 1],
                "keypoints": [float(c.mean()) + 0.5, float(r.mean()) + 0.5, 2],
                "area": float(len(r)),
            }
        )
    annotations.append({"id": 999, "bbox": [-50.0, -50.0, 10.0, 10.0], "keypoints": [-40.0, -40.0, 2]})
    layers, moved, about = warp(
        wide, {"instance": (ids[..., None], "a"), "boxes": ({"annotations": annotations, "info": "kept"}, "b")}
    )
    assert moved["info"] == "kept" and about["kinds"]["boxes"]["boxes_dropped_outside"] == 1
    for a in moved["annotations"]:
        mine = layers["instance.id"] == a["id"]
        r, c = rows[mine], cols[mine]
        # the box holds the label's pixels (COCO: a pixel spans c … c + 1), whose dithered edges may reach a pixel
        # beyond it, and hugs them (a disc's tip, a pixel or two, may round either way)
        x, y, w, h = a["bbox"]
        assert x - 1 <= c.min() and c.max() + 1 <= x + w + 1 and y - 1 <= r.min() and r.max() + 1 <= y + h + 1
        assert w <= np.ptp(c) + 1 + 3 and h <= np.ptp(r) + 1 + 3
        assert np.hypot(*(np.array(a["keypoints"][:2]) - 0.5 - centroid(mine))) < 0.2
        assert a["area"] == pytest.approx(mine.sum(), rel=0.05)
    hidden = {"annotations": [{"keypoints": [160.0, 108.0, 2, 500.0, 10.0, 2, 0, 0, 0]}]}
    _, moved, about = warp(wide, {"boxes": (hidden, "k")})
    assert moved["annotations"][0]["keypoints"][3:] == [0.0, 0.0, 0, 0, 0, 0]
    assert about["kinds"]["boxes"]["keypoints_moved_outside"] == 1


@pytest.fixture(scope="module")
def barrel(synthetic_grid):
    """A synthetic lens over ±2° with barrel distortion: each node's chief ray 3 % of its squared field
    radius (relative to the corner's) inward, 4.8 px at the corners of a 320x216 frame."""
    fields = np.linspace(-2.0, 2.0, 9)
    ideal = synthetic_grid.focal_mm * np.tan(np.radians(np.stack(np.meshgrid(fields, fields[::-1]), axis=-1))) * 1e3
    squared = (ideal**2).sum(axis=-1, keepdims=True) / (ideal**2).sum(axis=-1).max()
    psf = synthetic_grid.gaussian(15, 4.0, 2.0)
    return synthetic_grid.from_psfs(
        np.broadcast_to(psf, (1, 9, 9, 15, 15)), 2.0, (-0.03 * ideal * squared)[None], sampling="edges"
    )


@pytest.mark.parametrize("boundary", ["edge", "reflect", "zero"])
def test_the_valid_layer_is_where_the_source_lies_inside_the_frame(barrel, boundary):
    """`labels.valid` against an independent route: the output pixels inside the input frame's border moved
    forward by the mapping (a polygon); the labels beyond it follow the image's boundary rule (`zero`: 0)."""
    from matplotlib.path import Path as Polygon

    mapping = mapping_for(barrel, W, H)
    ids = discs() + 1  # no 0 in the input
    layers, _, about = warp(barrel, ids, boundary=boundary)
    edge = np.linspace(-0.5, W - 0.5, 4 * W), np.linspace(-0.5, H - 0.5, 4 * H)
    border = np.concatenate(
        [
            np.stack([edge[0], np.full(4 * W, -0.5)], 1),
            np.stack([np.full(4 * H, W - 0.5), edge[1]], 1),
            np.stack([edge[0][::-1], np.full(4 * W, H - 0.5)], 1),
            np.stack([np.full(4 * H, -0.5), edge[1][::-1]], 1),
        ]
    )
    polygon = Polygon(np.stack(mapping.forward(border[:, 0], border[:, 1]), axis=1))
    rows, cols = np.indices((H, W))
    inside = polygon.contains_points(np.stack([cols.ravel(), rows.ravel()], 1)).reshape(H, W)
    valid = layers["labels.valid"] == 1
    assert (~valid).sum() > 500 and (valid == inside).mean() > 0.999
    assert about["valid_fraction"] == pytest.approx(valid.mean())
    zero = set(np.unique(layers["instance.id"][~valid])) == {0.0}
    assert zero == (boundary == "zero") and set(np.unique(layers["instance.id"][valid])) <= set(np.unique(ids))


def test_depth_aware_labels_follow_each_distances_mapping():
    """With a depth grid each pixel's labels move by its own distance's chief rays: discs 2 m away before a
    plane at infinity through the wide angle, their warped ids on their light within 0.2 px (before the
    warp: up to 0.9 px off); the depth-aware path states its chief-ray offset too."""
    from solas_mi.convolution.depth import degrade_depth
    from solas_mi.psf.depth import depth_grid

    lens = Lens.load("wide-angle-22mm")
    g = depth_grid(
        lens,
        GridSpec(
            **GRID,
            wavelengths_nm=(lens.primary_wavelength,),
            field_range_deg=(40.0, 29.0),
            pitch_um=8.0,
            distances_m=(math.inf, 2.0),
        ),
    )
    ids = discs()
    depth = np.where(ids > 0, 2.0, np.inf)
    meta = {}
    image = degrade_depth((ids > 0).astype(float), depth, g, meta=meta)
    layers, _, about = warp(g, ids, depth=depth)
    after, before = blob_errors(ids, layers["instance.id"], image, meta["kernel_size_px"] // 2 + 1)
    assert max(after) < 0.2 and max(before) > 0.8 and "1/distance" in about["mapping"]
    assert meta["max_chief_ray_offset_px"] == pytest.approx(about["max_chief_ray_offset_px"])


@pytest.mark.parametrize("kinds", [("instance",), ("depth", "flow"), "every image kind"])
def test_the_memory_estimate_covers_the_warp(wide, kinds):
    """`labels.memory_bytes` against the warp's peak allocation (tracemalloc), the values read included: at
    least it, at most twice it; every rule has its cost."""
    import tracemalloc

    from solas_mi.convolution.labels import RULE_BYTES, memory_bytes
    from solas_mi.labelkinds import KINDS, RULES

    kinds = tuple(k for k in KINDS if KINDS[k].extra["layers"]) if isinstance(kinds, str) else kinds
    tracemalloc.start()
    labels = {k: (np.ones((H, W, len(KINDS[k].extra["layers"]))) * (discs()[..., None] + 1), k) for k in kinds}
    warp(wide, labels)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak <= memory_bytes(H * W, kinds) <= 2 * peak
    assert set(RULE_BYTES) == set(RULES) and memory_bytes(H * W, []) == 0


def write_frame(tmp_path, shape=(H, W)):
    from solas_mi.imageio import write_png

    frame = tmp_path / "frame.png"
    write_png(frame, np.full((*shape, 3), 0.5))
    return frame


def test_bad_labels_are_refused_by_name_before_anything_is_written(tmp_path, wide):
    from solas_mi.convolution.output import degrade_file
    from solas_mi.imageio import write_exr
    from solas_mi.labelkinds import parse_label_files

    frame = write_frame(tmp_path)
    write_exr(tmp_path / "small.exr", {"instance.id": np.zeros((H - 1, W))})
    write_exr(tmp_path / "floats.exr", {"instance.id": np.full((H, W), 2.5)})
    write_exr(tmp_path / "d.exr", {"Z": np.full((H, W), -1.0)})
    (tmp_path / "rle.json").write_text(json.dumps({"annotations": [{"segmentation": {"counts": "x", "size": [2, 2]}}]}))
    cases = [
        ({"instance": tmp_path / "small.exr"}, f"are {W}x{H - 1} pixels; the frame .* is {W}x{H}"),
        ({"instance": tmp_path / "floats.exr"}, "value 2.5 at row 0, column 0 .*whole numbers"),
        ({"semantic": tmp_path / "missing.png"}, "missing.png' does not exist"),
        ({"boxes": tmp_path / "rle.json"}, "annotation 0 has a segmentation that is not a list of polygons"),
    ]
    out = tmp_path / "out.exr"
    for files, says in cases:
        with pytest.raises(SolasError, match=says):
            degrade_file(frame, wide, "grid.exr", out, tmp_path / "out.png", labels=files)
        assert not out.exists() and not (tmp_path / "out.png").exists() and not (tmp_path / "out.labels.exr").exists()
    for text, says in (
        ("colour=a.png", "KIND one of depth, normal"),
        ("instance=a.jpg", "ending in .png or"),
        ("instance=a.png,instance=b.png", "instance is given twice"),
    ):
        with pytest.raises(SolasError, match=says):
            parse_label_files(text, "--labels")
    with pytest.raises(SolasError, match="with {stem} beside each frame"):
        parse_label_files("instance=ids.png", "--label-pattern", pattern=True)
    with pytest.raises(SolasError, match=r"value -1\.0 .*depths are metres >= 0"):
        read_labels({"depth": tmp_path / "d.exr"}, (H, W), frame)


def test_the_degrade_command_writes_the_warped_labels_beside_the_frame(tmp_path, wide):
    from solas_mi.cli import main
    from solas_mi.imageio import read_exr, write_exr, write_png

    frame = write_frame(tmp_path)
    ids = discs()
    write_png(tmp_path / "ids.png", ids / 255.0, encoded=True)  # 8-bit ids as stored
    write_exr(tmp_path / "depth.exr", {"Z": np.full((H, W), 7.0)})
    (tmp_path / "boxes.json").write_text(json.dumps({"annotations": [{"bbox": [10, 10, 20, 20]}]}))
    wide.write(str(tmp_path / "grid.exr"))
    out = tmp_path / "out.exr"
    argv = [
        "degrade",
        str(frame),
        "--psf-grid",
        str(tmp_path / "grid.exr"),
        "-o",
        str(out),
        "--labels",
        f"instance={tmp_path / 'ids.png'},depth={tmp_path / 'depth.exr'},boxes={tmp_path / 'boxes.json'}",
    ]
    assert main(argv) == 0
    targets = label_outputs(out, ["instance", "boxes"])
    assert targets == {"layers": tmp_path / "out.labels.exr", "boxes": tmp_path / "out.boxes.json"}
    channels, meta = read_exr(targets["layers"])
    assert sorted(channels) == ["depth.Z", "instance.id", "labels.valid"]
    assert set(np.unique(channels["instance.id"])) <= set(np.unique(ids)) and np.allclose(channels["depth.Z"], 7.0)
    assert meta["labels"]["kinds"]["instance"]["rule"] == "pick"
    assert read_exr(out)[1]["labels"]["outputs"] == {k: str(v) for k, v in targets.items()}
    moved = json.loads(targets["boxes"].read_text())
    assert moved["annotations"][0]["bbox"] != [10, 10, 20, 20] and "solas_mi_labels" in moved
