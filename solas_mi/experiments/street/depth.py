"""Step (g) of the street experiment (`run`): the depth-aware convolution (`convolution.depth`) of the
ideal image with its depth map, against the lens renders focused at infinity and at the near focus,
with the render's noise removed (two seeds), as the number of depth layers grows.

Grids over distance: nodes spaced evenly in 1/distance from infinity to the nearest object (its
depth × NEAREST_MARGIN), LAYERS[i] intervals between them (LAYERS[i] + 1 nodes; "1 node" is the
single grid at infinity, today's convolution). The node sets are nested (16 intervals hold the nodes
of 8, 4, 2, 1), so the 17 grids of each focus are computed once. Field nodes DEPTH_GRID (columns,
rows), PSF pitch = pixel / 4 and DEPTH_PSF_SIZE samples: a 64-px window, which holds the blur of the
nearest objects (the doublet focused at infinity: ≈ 44 px at 7 m; the 160-sample window of the
single-distance grids spans 20 px).

Units: each render is in its own focus's lens-camera unit (the refocused lens's on-axis irradiance is
(N/N')² of the file's, N the exit pupil's working f-number: 2.5 % less at 20 m for the doublet), so each
focus's convolution is divided by k times that (`focus_unit`).

Depth: the depth map is the distance along each pixel's ray; the grids' object distance is along the
axis, z = t·cos θ. Errors: relative RMSE (image − mean of the two renders)/RMS(render) over near
(closer than 1.5 × the near focus) and far (beyond FAR_M) pixels, the renders' noise removed in
quadrature: the per-pixel variance of the mean of two seeds is (r1 − r2)²/4. Near and far by both the
ideal depth map and the render's own (the depth scene through the lens camera: the mean distance along
each pixel's rays): a pixel at a silhouette that one calls near and the other not mixes both sides'
light and is neither (the ideal map's classes alone: the "…_pinhole_depth" fields).
"""

from __future__ import annotations

import math
import time

import numpy as np

LAYERS = (1, 2, 4, 8, 16)  # intervals between depth nodes
DEPTH_GRID = (16, 12)  # field nodes (columns, rows)
DEPTH_PSF_SIZE = 256
NEAREST_MARGIN = 0.95


def axial_depth(depth: np.ndarray, fov_deg: float) -> np.ndarray:
    """Distance along the axis (z) of a depth map of distances along each pixel's ray (inf stays inf)."""
    from ...validation.inputs import tangent_cos3

    h, w = depth.shape
    return depth * tangent_cos3(w, h, fov_deg) ** (1.0 / 3.0)


def denoised_errors(
    image: np.ndarray, renders: tuple[np.ndarray, np.ndarray], near: np.ndarray, far: np.ndarray
) -> dict:
    """Relative RMSE of `image` against the mean of two renders, all / near / far pixels, with and
    without the renders' noise (variance (r1 − r2)²/4 per pixel) removed in quadrature."""
    r1, r2 = (r.astype(np.float64) for r in renders)
    ref = 0.5 * (r1 + r2)
    err2, noise2 = (image - ref) ** 2, 0.25 * (r1 - r2) ** 2
    rms = math.sqrt(float(np.mean(ref**2)))
    out = {}
    for name, mask in (("all", np.ones_like(near)), ("near", near), ("far", far)):
        if not mask.any():
            out[f"rel_rmse_{name}"] = out[f"rel_rmse_{name}_raw"] = None
            continue
        e, n = float(np.mean(err2[mask])), float(np.mean(noise2[mask]))
        out[f"rel_rmse_{name}"] = math.sqrt(max(0.0, e - n)) / rms
        out[f"rel_rmse_{name}_raw"] = math.sqrt(e) / rms
        out[f"rel_bias_{name}"] = float(np.mean((image - ref)[mask])) / rms
    return dict(
        out,
        near_pixels=int(near.sum()),
        far_pixels=int(far.sum()),
        render_noise_rel=math.sqrt(float(np.mean(noise2))) / rms,
    )


def check_layers(layers) -> tuple[int, ...]:
    """Counts of intervals between depth nodes, increasing, each dividing the largest (nested nodes)."""
    from ...errors import SolasError

    out = tuple(layers)
    if not out or any(not isinstance(n, int) or n < 1 or out[-1] % n for n in out) or list(out) != sorted(set(out)):
        raise SolasError(
            f"depth layers {layers!r} must be increasing whole numbers >= 1, each dividing the "
            "largest (the node sets are nested), e.g. 1,2,4,8,16"
        )
    return out


def depth_rows(
    st, weighted: np.ndarray, depth: np.ndarray, k: float, renders: dict, masks: dict, field_range: tuple[float, float]
) -> tuple[dict, dict]:
    """(images, error rows) of the depth-aware convolution for each focus ("infinity", the near focus)
    and each count of intervals in st.s.depth_layers; `renders`: focus label → (seed 0, seed 1) renders;
    `masks`: focus label → near and far by the ideal depth map, then by the render's own (`masked`)."""
    from ...optics.focus import focused
    from ...psf.spec import inverse_spaced

    z = axial_depth(depth, st.fov)
    nearest = NEAREST_MARGIN * float(z[np.isfinite(z)].min())
    layers = check_layers(st.s.depth_layers)
    nodes = inverse_spaced(layers[-1] + 1, nearest)
    images, rows = {}, {}
    lenses = {"infinity": st.lens, f"{st.near_focus:g} m": focused(st.lens, 1e3 * st.near_focus)}
    for label, lens in lenses.items():
        unit = k * focus_unit(st.lens, lens, st.primary)
        full = st.timed(
            f"(g) PSF grids over {len(nodes)} distances, focus {label}", _grid, st, lens, nodes, field_range
        )
        for count in (0, *layers):
            step = layers[-1] // count if count else None
            grid = full.subset(list(range(0, len(nodes), step)) if step else [0])
            name = f"depth-aware interp {DEPTH_GRID[0]}x{DEPTH_GRID[1]}, {count + 1} nodes, focus {label}"
            image, seconds = _convolve(weighted, z, grid, unit)
            rows[f"{name} vs render {label}"] = dict(
                masked(image, renders[label], *masks[label]),
                intervals=count,
                nodes=count + 1,
                seconds=seconds,
                nearest_node_m=nearest,
                unit_k=unit,
            )
            if count == layers[-1]:
                images[name] = image
                for suffix, options in (
                    (", no occlusion", {"occlusion": "none"}),
                    (", silhouettes' depth as given", {"silhouette": "as-given"}),
                ):
                    other, seconds = _convolve(weighted, z, grid, unit, **options)
                    rows[f"{name}{suffix} vs render {label}"] = dict(
                        masked(other, renders[label], *masks[label]),
                        intervals=count,
                        nodes=count + 1,
                        seconds=seconds,
                        **options,
                    )
    return images, rows


def masked(
    image: np.ndarray, renders: tuple, near: np.ndarray, far: np.ndarray, near_lens: np.ndarray, far_lens: np.ndarray
) -> dict:
    """`denoised_errors` on the pixels both the ideal depth map (`near`, `far`) and the render's own
    (`near_lens`, `far_lens`: by the mean distance along each pixel's rays through the lens) call near or
    far (a pixel at a silhouette whose light mixes both sides is neither), and on the ideal map's alone
    ("…_pinhole_depth")."""
    both = denoised_errors(image, renders, near & near_lens, far & far_lens)
    alone = denoised_errors(image, renders, near, far)
    return dict(
        both,
        near_far="by the ideal depth map and the render's own (through the lens) alike",
        **{
            f"{key}_pinhole_depth": alone[key] for key in ("rel_rmse_near", "rel_rmse_far", "near_pixels", "far_pixels")
        },
    )


def focus_unit(lens, refocused, wavelength_nm: float) -> float:
    """The lens camera's unit (a lossless lens's on-axis irradiance: the exit pupil's solid angle seen
    from the film centre) of `refocused` against that of `lens`: (N / N')², N the exit pupil's working
    f-number (image plane − exit pupil over its diameter), which grows as the image plane moves back."""
    from ...optics.paraxial import paraxial

    return (
        paraxial(lens, wavelength_nm).exit_pupil_f_number / paraxial(refocused, wavelength_nm).exit_pupil_f_number
    ) ** 2


def _grid(st, lens, nodes, field_range):
    from ...optics.camera import pinhole_focal_mm
    from ...psf.depth import depth_grid
    from ...psf.spec import GridSpec

    spec = GridSpec(
        grid=(DEPTH_GRID[1], DEPTH_GRID[0]),
        wavelengths_nm=[st.primary],
        field_range_deg=field_range,
        method="geometric",
        normalization="none",
        pitch_um=st.pixel_um / 4,
        size=DEPTH_PSF_SIZE,
        distances_m=nodes,
    )
    # one camera for both focus settings: the lens renders' pixel pitch is set for the lens as its file
    # focuses it; refocused, the image's change of scale (0.5 % at 20 m) is part of the chief-ray offsets
    # the ideal camera's pinhole sits at surface 1's vertex (`lens_camera`'s origin), the lens sees from its
    # entrance pupil (153 mm behind it for the doublet): 0.8 % of parallax at 20 m
    return depth_grid(lens, spec, camera_focal_mm=pinhole_focal_mm(st.lens, st.fov), viewpoint_mm=0.0)


def _convolve(
    weighted: np.ndarray, z: np.ndarray, grid, k: float, occlusion: str = "filled", silhouette: str = "nearest"
):
    from ...convolution.depth import degrade_depth

    start = time.perf_counter()
    image = degrade_depth(weighted, z, grid, "edge", occlusion=occlusion, silhouette=silhouette) / np.float32(k)
    return image, time.perf_counter() - start
