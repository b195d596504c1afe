"""Batch work: many images degraded by one PSF grid (computed once, cached), or images and scene
files rendered through a lens over a sweep of lenses, focus, sensors and spp; on local processes or a
Dask cluster, resumable, with a manifest (`batch.json`) of every item (`jobs`), the PSF-grid cache
(`cache`), one item's work (`work`), the executors (`runner`), the batches (`degrade`, `render`) and
`solas-mi batch` (`commands`).

    degrade_batch(["frames/"], "out/", DegradeSpec(grid_spec=GridSpec(grid=(8, 8))), lens="solas-doublet", workers=2)
    render_batch(["frames/", "street.xml"], "out/", lens=["solas-doublet", "cooke-triplet"], spp=[16, 64])
"""

from ..lazy import lazy_exports

__all__ = ["GridCache", "Manifest", "degrade_batch", "render_batch"]
__getattr__ = lazy_exports(
    __name__, {"GridCache": ".cache", "Manifest": ".jobs", "degrade_batch": ".degrade", "render_batch": ".render"}
)
