"""A RAW frame from an irradiance image: the sensor's chain of stages (`chain`), deterministic for a seed.

Per pixel (EMVA 1288 release 4.0, section 2): the mean photo-electrons μ_e = η μ_p of the pixel's
filter (`photons.PhotonConversion`: cfa.mosaic of exposure.photons with the effective quantum efficiencies
Q[f, c] of the `qe` module), then each readout (`readout`): the PRNU gain, Poisson photo-electrons and dark
electrons, the full well, the DSNU offset and Gaussian read noise, the ADC y = round(K e + black) clipped to
[0, 2^bits − 1]; an HDR sensor merges its readouts (`merge`) and compands the result (`compander`); dead and
hot pixels are a stage of their own (`defects`). The fixed
pattern (PRNU, DSNU) comes from the seed alone, so every frame of one seed shares it; the temporal noise
comes from (seed, frame). A flat sensor (`model.SensorModel`) is the chain of one readout (`chain.chain_of`).
"""

import numpy as np

from ..errors import SolasError
from .chain import SensorChain, chain_of
from .model import SensorModel
from .readout import charge_pattern, charge_streams

MAX_SEED = 2**31 - 1  # a camera's seed (a batch's too), its frames' numbers 56 bits (`isp.camera`)


def as_chain(sensor: SensorModel | SensorChain) -> SensorChain:
    """The chain of stages of a sensor (a flat one's: `chain.chain_of`)."""
    if isinstance(sensor, SensorChain):
        return sensor
    if not isinstance(sensor, SensorModel):
        raise SolasError(f"sensor {sensor!r} must be a SensorModel or a SensorChain")
    return chain_of(sensor)


def mean_electrons(sensor: SensorModel | SensorChain, irradiance: np.ndarray, exposure_s: float) -> np.ndarray:
    """The noise-free photo-electrons of each pixel (H, W) of an irradiance image (H, W, 3) in W/m²,
    before PRNU and the full well (of the reference photodiode over the whole exposure)."""
    return sensor.photons.mean_electrons(irradiance, exposure_s)


def fixed_pattern(model: SensorModel, shape: tuple[int, int], seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The per-pixel gain (mean 1, spread `prnu`) and offset (e⁻, mean 0, spread `dsnu_e`) of a flat sensor
    of seed `seed`."""
    readout = as_chain(model).readouts[0]
    gain, (offset,) = charge_pattern([readout], shape, charge_streams(0, readout.charge, seed, 0)[0])
    return gain, offset


def _whole(value) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool) and value >= 0


def check_seed(seed) -> None:
    """SolasError unless `seed` is a sensor's seed: an integer from 0 to `MAX_SEED`."""
    if not _whole(seed) or seed > MAX_SEED:
        raise SolasError(f"sensor seed {seed!r} must be an integer >= 0 and at most 2^31 - 1")


def check_frame(frame) -> None:
    """SolasError unless `frame` is a frame number: an integer >= 0."""
    if not _whole(frame):
        raise SolasError(f"sensor frame {frame!r} must be an integer >= 0")


def capture_readouts(
    sensor: SensorModel | SensorChain, irradiance: np.ndarray, exposure_s: float, seed: int, frame: int = 0
) -> list[np.ndarray]:
    """Each readout's frame (H, W, uint16 DN), in the chain's order, before any merge."""
    check_seed(seed)
    check_frame(frame)
    return as_chain(sensor).readout_frames(irradiance, exposure_s, seed, frame)


def capture(
    sensor: SensorModel | SensorChain, irradiance: np.ndarray, exposure_s: float, seed: int, frame: int = 0
) -> np.ndarray:
    """The RAW frame a sensor gives for an image-plane irradiance image: photons → electrons → DN.

    Shot, dark and read noise, PRNU and DSNU, full well, conversion gain, ADC and black level, through the
    sensor's chain of stages (an HDR sensor's readouts merged and companded; [the sensor](../details/sensor.md));
    the same seed and frame give the same frame.

    Parameters
    ----------
    sensor : SensorModel or SensorChain
        The sensor.
    irradiance : numpy.ndarray, callable or timing.FlickeringScene
        (H, W, 3) image-plane irradiance (W/m²) of the channels R, G, B; or a scene that changes during the
        frame, each row taking its window of it through the sensor's shutter (`timing`).
    exposure_s : float
        The exposure time (s).
    seed : int
        The sensor's seed (0 to `MAX_SEED`): it fixes the pixels' gain and offset patterns.
    frame : int, default 0
        The frame's number: its temporal noise.

    Returns
    -------
    numpy.ndarray
        (H, W) DN, the mosaic of the sensor's CFA: uint16, or uint32 for a merged signal not companded.

    Raises
    ------
    SolasError
        For a bad seed or frame number.

    Examples
    --------
    >>> import numpy as np
    >>> from solas_mi.sensor import load_sensor
    >>> from solas_mi.sensor.capture import capture
    >>> raw = capture(load_sensor("ar0132at"), np.full((4, 6, 3), 0.1), 0.01, seed=1)
    >>> raw.shape, raw.dtype.name
    ((4, 6), 'uint16')
    """
    chain = as_chain(sensor)
    return chain.output(capture_readouts(chain, irradiance, exposure_s, seed, frame))
