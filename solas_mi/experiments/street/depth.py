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

Depth: the depth map is the distance along each pixel's ray; the grids' object distance is along the
axis, z = t·cos θ. Errors: relative RMSE (image − mean of the two renders)/RMS(render) over near
(closer than 1.5 × the near focus) and far (beyond FAR_M) pixels, the renders' noise removed in
quadrature: the per-pixel variance of the mean of two seeds is (r1 − r2)²/4.
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


def denoised_errors(image: np.ndarray, renders: tuple[np.ndarray, np.ndarray], near: np.ndarray,
                    far: np.ndarray) -> dict:
    """Relative RMSE of `image` against the mean of two renders, all / near / far pixels, with and
    without the renders' noise (variance (r1 − r2)²/4 per pixel) removed in quadrature."""
    r1, r2 = (r.astype(np.float64) for r in renders)
    ref = 0.5 * (r1 + r2)
    err2, noise2 = (image - ref) ** 2, 0.25 * (r1 - r2) ** 2
    rms = math.sqrt(float(np.mean(ref ** 2)))
    out = {}
    for name, mask in (("all", np.ones_like(near)), ("near", near), ("far", far)):
        if not mask.any():
            out[f"rel_rmse_{name}"] = out[f"rel_rmse_{name}_raw"] = None
            continue
        e, n = float(np.mean(err2[mask])), float(np.mean(noise2[mask]))
        out[f"rel_rmse_{name}"] = math.sqrt(max(0.0, e - n)) / rms
        out[f"rel_rmse_{name}_raw"] = math.sqrt(e) / rms
        out[f"rel_bias_{name}"] = float(np.mean((image - ref)[mask])) / rms
    return dict(out, near_pixels=int(near.sum()), far_pixels=int(far.sum()),
                render_noise_rel=math.sqrt(float(np.mean(noise2))) / rms)


def check_layers(layers) -> tuple[int, ...]:
    """Counts of intervals between depth nodes, increasing, each dividing the largest (nested nodes)."""
    from ...errors import SolasError

    out = tuple(layers)
    if not out or any(not isinstance(n, int) or n < 1 or out[-1] % n for n in out) or list(out) != sorted(set(out)):
        raise SolasError(f"depth layers {layers!r} must be increasing whole numbers >= 1, each dividing the "
                         "largest (the node sets are nested), e.g. 1,2,4,8,16")
    return out


def depth_rows(st, weighted: np.ndarray, depth: np.ndarray, k: float, renders: dict, near: np.ndarray,
               far: np.ndarray, field_range: tuple[float, float]) -> tuple[dict, dict]:
    """(images, error rows) of the depth-aware convolution for each focus ("infinity", the near focus)
    and each count of intervals in st.s.depth_layers; `renders`: focus label → (seed 0, seed 1) renders."""
    from ...optics.focus import focused
    from ...psf.spec import inverse_spaced

    z = axial_depth(depth, st.fov)
    nearest = NEAREST_MARGIN * float(z[np.isfinite(z)].min())
    layers = check_layers(st.s.depth_layers)
    nodes = inverse_spaced(layers[-1] + 1, nearest)
    images, rows = {}, {}
    lenses = {"infinity": st.lens, f"{st.near_focus:g} m": focused(st.lens, 1e3 * st.near_focus)}
    for label, lens in lenses.items():
        full = st.timed(f"(g) PSF grids over {len(nodes)} distances, focus {label}", _grid, st, lens, nodes,
                        field_range)
        for count in (0, *layers):
            step = layers[-1] // count if count else None
            grid = full.subset(list(range(0, len(nodes), step)) if step else [0])
            name = f"depth-aware interp {DEPTH_GRID[0]}x{DEPTH_GRID[1]}, {count + 1} nodes, focus {label}"
            image, seconds = _convolve(weighted, z, grid, k)
            rows[f"{name} vs render {label}"] = dict(denoised_errors(image, renders[label], near, far),
                                                     intervals=count, nodes=count + 1, seconds=seconds,
                                                     nearest_node_m=nearest)
            if count == layers[-1]:
                images[name] = image
                plain, seconds = _convolve(weighted, z, grid, k, "none")
                rows[f"{name}, no occlusion vs render {label}"] = dict(
                    denoised_errors(plain, renders[label], near, far), intervals=count, nodes=count + 1,
                    seconds=seconds, occlusion="none")
    return images, rows


def _grid(st, lens, nodes, field_range):
    from ...optics.camera import pinhole_focal_mm
    from ...psf.depth import depth_grid
    from ...psf.spec import GridSpec

    spec = GridSpec(grid=(DEPTH_GRID[1], DEPTH_GRID[0]), wavelengths_nm=[st.primary], field_range_deg=field_range,
                    method="geometric", normalization="none", pitch_um=st.pixel_um / 4, size=DEPTH_PSF_SIZE,
                    distances_m=nodes)
    # one camera for both focus settings: the lens renders' pixel pitch is set for the lens as its file
    # focuses it; refocused, the image's change of scale (0.5 % at 20 m) is part of the chief-ray offsets
    # the ideal camera's pinhole sits at surface 1's vertex (`lens_camera`'s origin), the lens sees from its
    # entrance pupil (153 mm behind it for the doublet): 0.8 % of parallax at 20 m
    return depth_grid(lens, spec, camera_focal_mm=pinhole_focal_mm(st.lens, st.fov), viewpoint_mm=0.0)


def _convolve(weighted: np.ndarray, z: np.ndarray, grid, k: float, occlusion: str = "filled"):
    from ...convolution.depth import degrade_depth

    start = time.perf_counter()
    image = degrade_depth(weighted, z, grid, "edge", occlusion=occlusion) / np.float32(k)
    return image, time.perf_counter() - start
