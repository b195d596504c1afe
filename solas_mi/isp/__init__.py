"""The image processor: a sensor's RAW frame → an 8-bit sRGB frame, each stage optional and named in
the metadata (after the sensor, before the metrics in the import order).

- `black`: black-level subtraction, the signal scaled to the sensor's saturation (1.0 = saturated).
- `white`: white-balance gains, their methods by name (`white.METHODS`).
- `demosaic`: demosaicing methods by name (`demosaic.METHODS`) over the colour-demosaicing package, one
  dispatcher routing each method's own options.
- `ccm`: the colour correction matrix, from the sensor's channel responses or given.
- `tone`: the tone curves by name (`tone.CURVES`) and the 8-bit frame.
- `pipeline`: `ISP`, the processor's description (``default`` or a small TOML), and `develop`.
- `camera`: `Camera`, a sensor, exposure, processor and seed that a batch's frames go through.
"""

from ..lazy import lazy_exports

__all__ = ["Camera", "ISP", "develop", "load_camera", "load_isp"]
__getattr__ = lazy_exports(
    __name__,
    {
        "ISP": ".pipeline",
        "develop": ".pipeline",
        "load_isp": ".pipeline",
        "Camera": ".camera",
        "load_camera": ".camera",
    },
)
