"""Experiments that run the whole pipeline on shipped scenes: `street` (the SOLAS paper's natural-scene
SFR experiment on a procedural 3D street: `scene` writes it, `framings` points each lens at it, `run`
renders and degrades it, `measure` measures it, `prediction` predicts MTF50 from the PSF grid)."""

__all__: list[str] = []  # run from the command line (its `commands`): no Python API of its own
