"""The street experiment: `scene` (the procedural street as Mitsuba XML) → `framings` (a camera pose per
lens) → `run` (ideal image, PSF-grid convolutions, lens renders) → `measure` (NS-SFR per annulus beside
`prediction`, error maps, tables)."""

__all__: list[str] = []  # run from the command line (`solas-mi experiment street`): no Python API of its own
