"""Test inputs of the image processor: the noise-free RAW of a sensor, and a colour chart."""

from functools import lru_cache

import numpy as np

from solas_mi.isp.black import saturation_dn
from solas_mi.sensor.capture import mean_electrons
from solas_mi.sensor.model import SensorModel

EXPOSURE_S = 0.01


def ideal_raw(model: SensorModel, irradiance: np.ndarray, exposure_s: float = EXPOSURE_S) -> np.ndarray:
    """The sensor's RAW (float DN) with every noise off and no rounding: K · min(μ_e, full well) + black."""
    electrons = np.minimum(mean_electrons(model, irradiance, exposure_s), model.full_well_e)
    return model.gain_dn_per_e * electrons + model.black_level_dn


def unit_irradiance(model: SensorModel, exposure_s: float = EXPOSURE_S) -> float:
    """The irradiance (W/m², every channel) whose signal at the reference filter (G, or C of the clear
    patterns) is the saturation signal: the developed frame's linear 1.0 for a sensor's own CCM."""
    reference = "C" if "C" in model.cfa else "G"
    flat = np.ones((2, 2, 3))
    sites = dict(zip(model.cfa, mean_electrons(model, flat, exposure_s).ravel()))
    return saturation_dn(model) / (model.gain_dn_per_e * sites[reference])


@lru_cache(maxsize=1)
def chart_linear() -> np.ndarray:
    """Linear sRGB (24, 3) of the ColorChecker's spectral reflectances (colour-science's "ColorChecker N
    Ohta") under CIE D65, a perfect white of Y = 1."""
    import colour

    shape = colour.SpectralShape(360, 780, 5)  # every spectrum on one grid (colour aligns them, with a warning, else)
    sds = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    xyz = np.array([colour.sd_to_XYZ(sd.copy().align(shape), cmfs, d65) for sd in sds.values()]) / 100.0
    white = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    return colour.XYZ_to_RGB(xyz, colour.RGB_COLOURSPACES["sRGB"], white, apply_cctf_decoding=False)


def chart_image(patch: int = 32) -> np.ndarray:
    """The chart as an image: 4 rows × 6 columns of `patch` × `patch` pixels, linear sRGB clipped to
    [0, 1] (the cyan patch lies outside sRGB)."""
    colours = np.clip(chart_linear(), 0.0, 1.0).reshape(4, 6, 3)
    return np.repeat(np.repeat(colours, patch, axis=0), patch, axis=1)


def patch_means(frame: np.ndarray, patch: int = 32, margin: int = 8) -> np.ndarray:
    """The mean (24, 3) of each patch's centre, `margin` pixels in from its edges."""
    cells = frame.reshape(4, patch, 6, patch, 3)[:, margin : patch - margin, :, margin : patch - margin]
    return cells.mean(axis=(1, 3)).reshape(24, 3)


def delta_e(srgb_a: np.ndarray, srgb_b: np.ndarray) -> np.ndarray:
    """CIEDE2000 between two sets of sRGB-encoded [0, 1] colours."""
    import colour

    def lab(srgb):
        return colour.XYZ_to_Lab(colour.sRGB_to_XYZ(srgb))

    return colour.delta_E(lab(srgb_a), lab(srgb_b), method="CIE 2000")
