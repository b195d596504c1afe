"""What the street experiment's far error is made of (step (g), the lens focused at infinity, 17 nodes).

One run of each variant through the experiment's own code paths (`experiments.street.run`, `.depth`),
against the two seeds of the render (render noise removed in quadrature, as step (g) does; its size is
sqrt(raw² − denoised²)):

- field sampling: the same 17 depth nodes on 16×12 (step (g) as it is), 24×18 and 32×24 field nodes;
- the pixel model: the ideal image with the scene's Gaussian film filter (σ 0.5 px, step (g)'s) or
  rendered with a box film filter. The convolution treats its input
  as piecewise constant and averages over the output pixel (a tent, 1/6 px² of variance per axis) on
  top of the ideal image's own filter; the render filters the irradiance once, with the Gaussian (0.25
  px²). With a box ideal the convolution's three boxes have 3/12 = 0.25 px²: the pixel model matched to
  the render's to second order.

    python benchmarks/street_far_error.py [WIDTHxHEIGHT] [OUT_DIR]      # default 1280x960 out/street_far_error

Writes OUT_DIR/far_error.json (step (g)'s error fields per variant, grid and convolution seconds).
Several minutes on 2 cores (four 64-spp renders, three field grids over 17 distances).
"""

from __future__ import annotations

import math
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from solas_mi import jsonio
from solas_mi.experiments.street import depth as D
from solas_mi.experiments.street import run as R
from solas_mi.experiments.street.measure import FAR_M
from solas_mi.optics.camera import pinhole_focal_mm
from solas_mi.optics.illumination import axis_irradiance, ideal_irradiance
from solas_mi.optics.lens import Lens
from solas_mi.psf.spec import inverse_spaced
from solas_mi.render.mitsuba import spectral
from solas_mi.validation.inputs import tangent_cos3

FIELD_GRIDS = ((16, 12), (24, 18), (32, 24))  # 64x48 nodes over 17 distances would hold 14 GB of PSFs
KEYS = (
    "rel_rmse_near",
    "rel_rmse_far",
    "rel_rmse_far_raw",
    "far_noise",
    "rel_rmse_near_pinhole_depth",
    "rel_rmse_far_pinhole_depth",
    "rel_bias_far",
)


def box_ideal(st, xml: Path) -> np.ndarray:
    """The ideal image of the experiment's scene with a box film filter."""
    root = ET.parse(xml).getroot()
    root.find("sensor/film/rfilter").set("type", "box")
    box_xml = st.out / "scene_box.xml"
    box_xml.write_text(ET.tostring(root, encoding="unicode"))
    band = R.BAND_NM if spectral(st.variant) else 1.0
    return st.timed("ideal, box filter", R._render, box_xml, st.variant, None, st.params, st.s.spp_ideal)[..., 0] / band


def main(size: str = "1280x960", out: str = "out/street_far_error") -> dict:
    w, h = (int(v) for v in size.split("x"))
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    lens = Lens.load("solas-doublet")
    st = R._Steps(lens, out_dir, R.Settings(width=w, height=h), lambda m: print(m, file=sys.stderr, flush=True))
    xml, ideal, depth = R._ideal_and_depth(st)
    ideals = {"gaussian": ideal, "box": box_ideal(st, xml)}
    lens_params = {key: v for key, v in st.params.items() if key != "fov"}
    options = {"response": f"mono:{st.primary:g}", "pitch_um": st.pixel_um}
    renders = tuple(
        st.timed(
            f"lens render, focus at infinity, seed {seed}",
            R._render,
            xml,
            st.variant,
            lens,
            lens_params | {"spp": str(st.s.spp_lens)},
            st.s.spp_lens,
            seed,
            **options,
        )[..., 0]
        for seed in (0, 1)
    )
    through = st.timed(
        "depth through the lens",
        R._render,
        out_dir / "depth.xml",
        st.variant,
        lens,
        lens_params | {"spp": str(st.s.spp_depth)},
        st.s.spp_depth,
        0,
        **options,
    )[..., -1]
    near_m = 1.5 * st.near_focus
    masks = (depth < near_m, depth > FAR_M, through < near_m, through > FAR_M)
    k = axis_irradiance(lens, st.primary) / ideal_irradiance(lens, pinhole_focal_mm(lens, st.fov), st.primary)
    field_range = (st.fov, math.degrees(math.atan(math.tan(math.radians(st.fov)) * h / w)))
    z = D.axial_depth(depth, st.fov)
    nodes = inverse_spaced(17, D.NEAREST_MARGIN * float(z[np.isfinite(z)].min()))
    rows = {}
    for field_nodes in FIELD_GRIDS:
        D.DEPTH_GRID = field_nodes
        start = time.perf_counter()
        grid = D._grid(st, lens, nodes, field_range)
        grid_seconds = time.perf_counter() - start
        for rfilter, ideal_image in ideals.items():
            image, seconds = D._convolve(ideal_image * tangent_cos3(w, h, st.fov), z, grid, k)
            row = D.masked(image, renders, *masks)
            row.update(
                grid_seconds=grid_seconds,
                seconds=seconds,
                far_noise=math.sqrt(max(0.0, row["rel_rmse_far_raw"] ** 2 - row["rel_rmse_far"] ** 2)),
            )
            label = f"{field_nodes[0]}x{field_nodes[1]}, {rfilter} ideal"
            rows[label] = row
            print(label, " ".join(f"{key} {100 * row[key]:.2f} %" for key in KEYS), flush=True)
        del grid
    (out_dir / "far_error.json").write_text(jsonio.dumps(dict(size=[w, h], variants=rows), indent=1))
    return rows


if __name__ == "__main__":
    main(*sys.argv[1:])
