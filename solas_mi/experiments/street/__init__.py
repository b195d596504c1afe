"""The street experiment: `scene` (the procedural street as Mitsuba XML) → `framings` (a camera pose per
lens) → `run` (ideal image, PSF-grid convolutions, lens renders) → `measure` (NS-SFR per annulus beside
`prediction`, error maps, tables)."""
