"""Image sharpness metrics: images → MTF50 (cy/px), per ROI and per radial annulus.

roi: the ROI an e-SFR measures (box, luminance, clipping, step-edge test); esfr: ISO 12233 e-SFR /
MTF50 of one slanted-edge ROI; nssfr: natural-scene SFR in radial annuli (annuli: their schemes);
targets: synthetic slanted-edge targets with a known MTF; commands: the CLI subcommands.
"""
