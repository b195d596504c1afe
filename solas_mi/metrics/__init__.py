"""Image sharpness metrics: images → MTF50 (cy/px), per ROI and per radial annulus.

roi: the ROI an e-SFR measures (box, luminance, clipping, step-edge test); esfr: ISO 12233 e-SFR /
MTF50 of one slanted-edge ROI (esfr_result: what it gives); nssfr: natural-scene SFR in radial annuli
(annuli: their schemes; nssfr_report: what it gives);
targets: synthetic slanted-edge targets with a known MTF; commands: the CLI subcommands.
"""

from ..lazy import lazy_exports

# `esfr.esfr` is not exported here: its module's own name would hide it once imported
__all__ = ["analytic_mtf50", "natural_scene_sfr", "slanted_edge"]
__getattr__ = lazy_exports(
    __name__, {"analytic_mtf50": ".targets", "natural_scene_sfr": ".nssfr", "slanted_edge": ".targets"}
)
