"""The sensor: image-plane irradiance → a one-channel RAW frame, following EMVA 1288 (release 4.0).

- `exposure`: irradiance (W/m²) and exposure time → photons per pixel; scene radiance → image
  irradiance through the camera equation (f-number, transmission).
- `model`: `SensorModel`, a sensor of one linear readout (the flat `[sensor]` table), validated on
  construction.
- `chain`: `SensorChain`, the sensor as an ordered list of stages (`STAGES`): the photon conversion
  (`photons`), readouts (`readout`: split pixels, dual conversion gain, multiple exposures), the HDR
  merge (`merge`) and companding (`compander`), defect pixels (`defects`), the shutter (`timing`).
- `timing`: exposure in time: global and rolling shutters, each row's window of a moving scene or of
  PWM-driven light (LED flicker).
- `rendered`: a Mitsuba scene rendered over the rows' windows: its PWM-driven emitters (named by id) and a
  camera moving during the frame (`render_in_time`); `poses`: the camera's pose over the frame.
- `commands`: `solas-mi camera` and `sensors`; `time_options`: the camera's --flicker and --image-motion;
  `scene_input`: the camera's scene-file input (--pwm-emitter, --camera-motion).
- `emva`: what EMVA 1288 predicts of one readout; `limits`: the numbers' ranges and checks.
- `cfa`: colour filter array patterns (RGGB and its turns, RCCB, RCCC) and the mosaic.
- `qe`: quantum efficiency curves, and the effective QE with which each filter sees each channel.
- `files`: a sensor in a TOML file, or a preset from `presets/` (public data sheets, sources cited).
- `capture`: photons → electrons → digital numbers through the chain, with shot, dark and read noise,
  PRNU, DSNU, full well, conversion gain, ADC bit depth and black level; deterministic for a seed.
"""

from ..lazy import lazy_exports

# `capture.capture` is not exported here: its module's own name would hide it once imported
__all__ = [
    "PWMSource",
    "RenderedParts",
    "SensorChain",
    "SensorModel",
    "Shutter",
    "load_sensor",
    "render_in_time",
    "render_parts",
]
__getattr__ = lazy_exports(
    __name__,
    {
        "PWMSource": ".timing",
        "RenderedParts": ".rendered",
        "SensorChain": ".chain",
        "SensorModel": ".model",
        "Shutter": ".timing",
        "load_sensor": ".files",
        "render_in_time": ".rendered",
        "render_parts": ".rendered",
    },
)
