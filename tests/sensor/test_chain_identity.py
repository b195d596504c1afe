"""Every sensor that existed before the chain of stages gives the same frames, bit for bit: each preset and
flat sensor file, through the chain (`capture`), against an independent re-implementation of the one-readout
path as it was (`legacy_capture` below: photons, mosaic, fixed pattern from [seed, 0], shot, dark and read
noise from [seed, 1, frame], full well, ADC), compared by the SHA-256 of the frames. (When this test was
written the same digests were also checked against main's own code in a worktree: equal.) A file that names
the stages of the flat form gives those frames too."""

import hashlib

import numpy as np
import pytest

from solas_mi.sensor.auto_exposure import AutoExposure
from solas_mi.sensor.capture import capture
from solas_mi.sensor.files import load_sensor, preset_names
from solas_mi.sensor.model import SensorModel
from solas_mi.sensor.qe import QECurve

PLANCK, LIGHT_SPEED = 6.62607015e-34, 299_792_458.0
CHANNELS = {"R": (0,), "G": (1,), "B": (2,), "C": (0, 1, 2)}


def legacy_mean_electrons(model: SensorModel, image: np.ndarray, seconds: float) -> np.ndarray:
    area = (model.pixel_pitch_um * 1e-6) ** 2
    wavelengths = model.wavelengths_nm if model.qe_curve is None else model.channel_wavelengths_nm
    energy = PLANCK * LIGHT_SPEED / (np.asarray(wavelengths, dtype=np.float64) * 1e-9)
    mu_p = np.maximum(image, 0.0) * (area * seconds / energy)
    if model.qe_curve is None:
        qe = {"R": model.qe_r, "G": model.qe_g, "B": model.qe_b, "C": model.qe_c}
        weights = np.zeros((4, 3))
        for i, f in enumerate("RGBC"):
            weights[i, list(CHANNELS[f])] = qe[f]
    else:
        weights = model.effective_qe()
    tile = np.array(["RGBC".index(f) for f in model.cfa]).reshape(2, 2)
    sites = np.tile(tile, ((image.shape[0] + 1) // 2, (image.shape[1] + 1) // 2))[: image.shape[0], : image.shape[1]]
    out = np.zeros(image.shape[:2])
    for index in range(4):
        here = sites == index
        if here.any():
            out[here] = mu_p[here] @ weights[index]
    return out


def legacy_capture(model: SensorModel, image: np.ndarray, seconds: float, seed: int, frame: int) -> np.ndarray:
    mu_e = legacy_mean_electrons(model, image, seconds)
    cap = 2.0 * model.full_well_e + 1000.0
    fixed = np.random.default_rng([seed, 0])
    gain = np.clip(1.0 + model.prnu * fixed.standard_normal(mu_e.shape), 0.0, None)
    offset = model.dsnu_e * fixed.standard_normal(mu_e.shape)
    rng = np.random.default_rng([seed, 1, frame])
    electrons = rng.poisson(np.minimum(gain * mu_e, cap)).astype(np.float64)
    electrons += rng.poisson(min(model.dark_current_e_s * seconds, cap), mu_e.shape)
    np.minimum(electrons, model.full_well_e, out=electrons)
    electrons += offset + model.read_noise_e * rng.standard_normal(mu_e.shape)
    dn = np.rint(model.gain_dn_per_e * electrons + model.black_level_dn)
    return np.clip(dn, 0, 2**model.bit_depth - 1).astype(np.uint16)


def legacy_auto_seconds(model: SensorModel, image: np.ndarray, percentile: float, fraction: float) -> float:
    rate = float(np.percentile(legacy_mean_electrons(model, image, 1.0), percentile))
    saturation_dn = float(min(model.gain_dn_per_e * model.full_well_e, 2**model.bit_depth - 1 - model.black_level_dn))
    return fraction * (saturation_dn / model.gain_dn_per_e) / (rate + model.dark_current_e_s)


def digest(frame: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(frame).tobytes() + str(frame.dtype).encode()).hexdigest()


def scene(shape=(48, 66)) -> np.ndarray:
    """Irradiance over five decades (W/m²), channels unequal, with a black corner and round-off below zero."""
    rows, cols = np.mgrid[0 : shape[0], 0 : shape[1]]
    level = 10.0 ** (-3.0 + 5.0 * cols / (shape[1] - 1))
    image = np.stack([level * (1.0 + 0.3 * np.sin(rows / 5.0)), 0.7 * level, 0.4 * level], axis=-1)
    image[:6, :6] = 0.0
    image[0, 0] = -1e-9
    return image


CURVE = QECurve.from_table(
    {
        "wavelength_nm": [380, 480, 540, 620, 780],
        "R": [0.02, 0.03, 0.1, 0.6, 0.3],
        "G": [0.05, 0.3, 0.7, 0.2, 0.05],
        "B": [0.4, 0.6, 0.15, 0.03, 0.02],
        "C": [0.5, 0.6, 0.7, 0.6, 0.4],
    }
)
FILES = {
    "defaults": SensorModel(),
    "rccb-10bit": SensorModel(cfa="RCCB", bit_depth=10, black_level_dn=0, gain_dn_per_e=0.05),
    "rccc-hot": SensorModel(cfa="RCCC", dark_current_e_s=5e4, prnu=0.05, dsnu_e=20.0, pixel_pitch_um=4.2),
    "curve": SensorModel(qe_r=None, qe_g=None, qe_b=None, qe_c=None, cfa="RCCB", qe_curve=CURVE),
    "adc-bound": SensorModel(full_well_e=50000, gain_dn_per_e=0.2, bit_depth=12),
}
SENSORS = {
    **{name: load_sensor(name) for name in preset_names() if isinstance(load_sensor(name), SensorModel)},
    **FILES,
}


@pytest.mark.parametrize("name", list(SENSORS))
def test_every_flat_sensor_gives_the_frames_it_gave(name):
    model = SENSORS[name]
    image = scene()
    for seconds, seed, frame in ((1e-3, 0, 0), (0.02, 7, 1), (0.3, 2**31 - 1, 2**55 + 3)):
        assert digest(capture(model, image, seconds, seed, frame)) == digest(
            legacy_capture(model, image, seconds, seed, frame)
        )
    auto, _ = AutoExposure(99.0, 0.8).choose(model, image)
    assert auto == legacy_auto_seconds(model, image, 99.0, 0.8)


def test_the_flat_presets_are_all_here():
    """Every preset of one linear readout is compared above (a preset that names stages is a new sensor)."""
    assert {"ar0132at", "imx255", "imx490", "kac12040", "mt9p001"} <= set(SENSORS)


FLAT_FIELDS = (
    "dark_current_e_s",
    "read_noise_e",
    "prnu",
    "dsnu_e",
    "full_well_e",
    "gain_dn_per_e",
    "bit_depth",
    "black_level_dn",
)


def test_a_file_naming_the_stages_of_a_flat_sensor_gives_its_frames(tmp_path):
    """A preset written as [sensor] (photon conversion) + one [[sensor.readout]] is the same sensor."""
    flat = load_sensor("imx490")
    lines = ["[sensor]", f"pixel_pitch_um = {flat.pixel_pitch_um!r}", f"cfa = {flat.cfa!r}".replace("'", '"')]
    lines += [f"{name} = {getattr(flat, name)!r}" for name in ("qe_r", "qe_g", "qe_b", "qe_c")]
    lines += [f"wavelengths_nm = {list(flat.wavelengths_nm)!r}", "[[sensor.readout]]"]
    lines += [f"{name} = {getattr(flat, name)!r}" for name in FLAT_FIELDS]
    (tmp_path / "staged.toml").write_text("\n".join(lines) + "\n", encoding="utf-8")
    staged = load_sensor(tmp_path / "staged.toml")
    assert not isinstance(staged, SensorModel) and [kind for kind, _ in staged.stages()] == ["photons", "readout"]
    image = scene()
    assert digest(capture(staged, image, 0.01, 3, 5)) == digest(legacy_capture(flat, image, 0.01, 3, 5))


def test_frames_in_a_row_draw_the_fixed_pattern_once_and_give_the_frames_they_gave(monkeypatch):
    """A batch's frames of one sensor and seed reuse its fixed pattern (drawn once: counted) and each frame is
    still the legacy one, bit for bit — also after another seed, another frame size or an HDR sensor came
    between, whose own patterns replace the held ones."""
    from solas_mi.sensor import readout

    drawn, original = [], readout.charge_pattern

    def counted(readouts, shape, rng):
        drawn.append(shape)
        return original(readouts, shape, rng)

    monkeypatch.setattr(readout, "charge_pattern", counted)
    model, hdr, image = SENSORS["defaults"], load_sensor("imx490-hdr"), scene()
    small = image[:20, :30]
    order = [(image, 4, 0), (image, 4, 1), (image, 4, 2), (image, 5, 0), (small, 4, 3), (image, 4, 3)]
    for frame_image, seed, frame in order:
        expected = legacy_capture(model, frame_image, 0.01, seed, frame)
        assert digest(capture(model, frame_image, 0.01, seed, frame)) == digest(expected)
        if frame == 1:
            capture(hdr, frame_image, 0.01, seed, frame)
    # frame 0 (frame 1 reuses it); the HDR sensor's two charges; frame 2 again; seed 5; the small frame; back
    assert drawn == [image.shape[:2]] * 5 + [small.shape[:2], image.shape[:2]]
    ((gain, offsets),) = readout._PATTERNS.values()
    assert not gain.flags.writeable and not offsets[0].flags.writeable
