"""Batch work: many images degraded by one PSF grid (computed once, cached), on local processes or
a Dask cluster, resumable, with a manifest (`batch.json`) of every item (`jobs`), the PSF-grid
cache (`cache`), the executors (`runner`), the batch itself (`degrade`) and `solas-mi batch`
(`commands`).

    degrade_batch(["frames/"], "out/", lens="solas-doublet", grid_options={"grid": "8x8"}, workers=2)
"""
from ..lazy import lazy_exports

__all__ = ["GridCache", "Manifest", "degrade_batch"]
__getattr__ = lazy_exports(__name__, {"GridCache": ".cache", "Manifest": ".jobs", "degrade_batch": ".degrade"})
