"""Image sharpness metrics.

esfr: ISO 12233 e-SFR / MTF50 of one slanted-edge ROI; nssfr: natural-scene SFR in radial annuli
(annuli: their schemes); targets: synthetic slanted-edge targets with a known MTF; commands: the CLI
subcommands.
"""
