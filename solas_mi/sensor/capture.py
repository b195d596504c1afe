"""A RAW frame from an irradiance image: the sensor's signal chain, deterministic for a seed.

Per pixel (EMVA 1288 release 4.0, section 2): the mean photo-electrons μ_e = η μ_p of the pixel's
filter (cfa.mosaic of exposure.photons with the effective quantum efficiencies Q[f, c] of the `qe`
module: η_f of the scalar model, or a QE curve's photon-weighted mean over each channel's band), times
the pixel's PRNU gain;
photo-electrons and dark electrons are Poisson; the well holds at most the full well; the readout
adds the pixel's DSNU offset and Gaussian read noise; the ADC gives y = round(K e + black) clipped to
[0, 2^bits − 1]. The fixed pattern (PRNU, DSNU) comes from the seed alone, so every frame of one
seed shares it; the temporal noise comes from (seed, frame).
"""
import numpy as np

from ..errors import SolasError
from .cfa import mosaic
from .exposure import photons
from .model import SensorModel

MAX_SEED = 2**31 - 1  # a camera's seed (a batch's too), its frames' numbers 56 bits (`isp.camera`)


def mean_electrons(model: SensorModel, irradiance: np.ndarray, exposure_s: float) -> np.ndarray:
    """The noise-free photo-electrons of each pixel (H, W) of an irradiance image (H, W, 3) in W/m²,
    before PRNU and the full well."""
    mu_p = photons(irradiance, exposure_s, model.pixel_pitch_um, model.channel_wavelengths_nm)
    return mosaic(mu_p, model.cfa, model.effective_qe())


def fixed_pattern(model: SensorModel, shape: tuple[int, int], seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The per-pixel gain (mean 1, spread `prnu`) and offset (e⁻, mean 0, spread `dsnu_e`) of seed `seed`."""
    rng = np.random.default_rng([seed, 0])
    gain = 1.0 + model.prnu * rng.standard_normal(shape)
    offset = model.dsnu_e * rng.standard_normal(shape)
    return np.clip(gain, 0.0, None), offset


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


def capture(model: SensorModel, irradiance: np.ndarray, exposure_s: float, seed: int, frame: int = 0) -> np.ndarray:
    """The RAW frame a sensor gives for an image-plane irradiance image: photons → electrons → DN.

    Shot, dark and read noise, PRNU and DSNU, full well, conversion gain, ADC and black level
    ([the sensor](../details/sensor.md)); the same seed and frame give the same frame.

    Parameters
    ----------
    model : SensorModel
        The sensor.
    irradiance : numpy.ndarray
        (H, W, 3) image-plane irradiance (W/m²) of the channels R, G, B.
    exposure_s : float
        The exposure time (s).
    seed : int
        The sensor's seed (0 to `MAX_SEED`): it fixes the pixels' gain and offset patterns.
    frame : int, default 0
        The frame's number: its temporal noise.

    Returns
    -------
    numpy.ndarray
        (H, W) uint16 DN, the mosaic of the sensor's CFA.

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
    check_seed(seed)
    check_frame(frame)
    mu_e = mean_electrons(model, irradiance, exposure_s)
    # past the full well the count is clipped anyway: capping the Poisson means at 2 × full well + 1000
    # keeps them within NumPy's Poisson range (the Chernoff bound puts the chance that the well then
    # fails to fill below e⁻⁷⁰⁰)
    cap = 2.0 * model.full_well_e + 1000.0
    gain, offset = fixed_pattern(model, mu_e.shape, seed)
    rng = np.random.default_rng([seed, 1, frame])
    electrons = rng.poisson(np.minimum(gain * mu_e, cap)).astype(np.float64)
    electrons += rng.poisson(min(model.dark_current_e_s * exposure_s, cap), mu_e.shape)
    np.minimum(electrons, model.full_well_e, out=electrons)
    electrons += offset + model.read_noise_e * rng.standard_normal(mu_e.shape)
    dn = np.rint(model.gain_dn_per_e * electrons + model.black_level_dn)
    return np.clip(dn, 0, model.white_level_dn).astype(np.uint16)
