"""HDR sensors as chains of readouts, against photon statistics in closed form (EMVA 1288 per readout): the
photon transfer of every readout (two-frame analysis, 1.5 %), the merged signal's SNR on both sides of each
transition and the dip between (0.2 dB), split pixels with dual conversion gain (the IMX490-class preset) and
multiple exposures; the compander's round trip within each segment's quantisation step."""

import math
from dataclasses import replace

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.sensor import emva
from solas_mi.sensor.capture import capture, capture_readouts
from solas_mi.sensor.cfa import FILTERS, site_map
from solas_mi.sensor.chain import SensorChain, chain_of
from solas_mi.sensor.compander import Compander
from solas_mi.sensor.files import load_sensor
from solas_mi.sensor.merge import Merge
from solas_mi.sensor.photons import PhotonConversion
from solas_mi.sensor.readout import Readout

SHAPE = (512, 512)
EXPOSURE = 0.01  # s
SPLIT = load_sensor("imx490-hdr")  # split pixels, each at two conversion gains: 4 readouts, 2 charges
PHOTONS = PhotonConversion(pixel_pitch_um=3.0)
# three exposures of one photodiode, each 1/16 of the one before (AR0820AT-class; values are assumptions)
EXPOSURES = SensorChain(
    PHOTONS,
    tuple(
        Readout(
            name=f"T{i + 1}",
            exposure_ratio=16.0**-i,
            full_well_e=12000,
            gain_dn_per_e=(4095 - 64) / 12000,
            read_noise_e=2.5,
            dark_current_e_s=50.0,
        )
        for i in range(3)
    ),
    Merge(bits=20),
)
CHAINS = {"split-pixel-dcg": SPLIT, "multi-exposure": EXPOSURES}


def green(frame: np.ndarray) -> np.ndarray:
    return frame[site_map("RGGB", frame.shape) == FILTERS.index("G")].astype(np.float64)


def flat_field(chain: SensorChain, electrons: float) -> np.ndarray:
    """A uniform irradiance giving `electrons` mean photo-electrons of the reference photodiode on a G site."""
    unit = chain.photons.mean_electrons(np.ones((2, 2, 3)), EXPOSURE)[0, 1]
    return np.full((*SHAPE, 3), electrons / unit)


def two_frames(chain, electrons, merged: bool):
    image = flat_field(chain, electrons)
    shoot = capture if merged else capture_readouts
    return shoot(chain, image, EXPOSURE, 11, 0), shoot(chain, image, EXPOSURE, 11, 1)


def temporal(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Mean and temporal variance of the G sites from two frames (EMVA 1288: the fixed pattern cancels)."""
    a, b = green(a), green(b)
    return 0.5 * (a.mean() + b.mean()), 0.5 * np.var(a - b)


@pytest.mark.parametrize("name", list(CHAINS))
def test_every_readout_follows_its_photon_transfer_line(name):
    """σ_y² = K² σ_d² + σ_q² + K (μ_y − μ_y.dark) per readout (eq. 6) within 1.5 %, wherever its mean lies below
    85 % of its saturation and its temporal noise passes 0.6 DN (EMVA 1288's condition for eq. 5's σ_q²)."""
    chain = CHAINS[name]
    checked = {r.name: 0 for r in chain.readouts}
    top = chain.saturation_e
    for electrons in np.geomspace(30.0, 0.8 * top, 9):
        frames = zip(*two_frames(chain, float(electrons), merged=False))
        for r, (a, b) in zip(chain.readouts, frames):
            mean, variance = temporal(a, b)
            expected = emva.temporal_variance_dn2(
                r.gain_dn_per_e, r.dark_variance_e2(EXPOSURE), mean, r.dark_mean_dn(EXPOSURE)
            )
            if mean - r.black_level_dn < 0.85 * r.saturation_dn and expected > 0.6**2:
                assert variance == pytest.approx(expected, rel=0.015), (r.name, electrons)
                checked[r.name] += 1
    assert min(checked.values()) >= 2, checked


def merged_snr_db(chain: SensorChain, electrons: float) -> float:
    """The merged signal's SNR (dB): its photo-signal (G_0 DN per reference photo-electron) over its temporal
    noise from two frames."""
    first = chain.readouts[0]
    _, variance = temporal(*two_frames(chain, electrons, merged=True))
    return 20 * math.log10(electrons * first.gain_dn_per_e * first.response / math.sqrt(variance))


def transitions(chain: SensorChain) -> list[float]:
    """The reference photo-electrons where the merge moves on: readout i reaches the merge's threshold of its
    saturation (a readout already saturated there is passed over: the IMX490-class small photodiode's high
    gain fills within the large one's low gain)."""
    switches = [
        (chain.merge.threshold * r.saturation_dn / r.gain_dn_per_e - r.dark_current_e_s * EXPOSURE * r.exposure_ratio)
        / r.response
        for r in chain.readouts[:-1]
    ]
    return [s for i, s in enumerate(switches) if s > max(switches[:i], default=0.0)]


@pytest.mark.parametrize("name", list(CHAINS))
def test_the_merged_snr_dips_at_each_transition_as_predicted(name):
    """Just before (0.9 ×) and after (1.1 ×) each transition the merged SNR is the readout's own (eq. 15 with
    the merged code's rounding) within 0.2 dB, and so is the step between: the dip where the next readout
    sees fewer electrons (a smaller photodiode, a shorter exposure), almost none between two gains."""
    chain = CHAINS[name]
    predicted = lambda e: 20 * math.log10(chain.merge.predicted_snr(chain.readouts, e, EXPOSURE))  # noqa: E731
    dips = []
    for switch in transitions(chain):
        before, after = merged_snr_db(chain, 0.9 * switch), merged_snr_db(chain, 1.1 * switch)
        assert before == pytest.approx(predicted(0.9 * switch), abs=0.2)
        assert after == pytest.approx(predicted(1.1 * switch), abs=0.2)
        dips.append(predicted(0.9 * switch) - predicted(1.1 * switch))
        assert before - after == pytest.approx(dips[-1], abs=0.2)
    assert len(dips) == {"split-pixel-dcg": 2, "multi-exposure": 2}[name] and max(dips) > 6.0


@pytest.mark.parametrize("name", list(CHAINS))
def test_the_snr_curve_against_exposure_time_follows_the_closed_form(name):
    """One irradiance, exposures from 30 e⁻ to 80 % of saturation (24 times, log-spaced; the dark current
    grows with each): the merged SNR within 0.2 dB of the closed form at every exposure 10 % or more from a
    transition (closer, a pixel's readout depends on its noise)."""
    chain = CHAINS[name]
    first = chain.readouts[0]
    image = flat_field(chain, 1000.0)[:256, :256]  # 1000 e⁻ of the reference photodiode at EXPOSURE
    switches = np.array(transitions(chain))
    checked = 0
    for electrons in np.geomspace(30.0, 0.8 * chain.saturation_e, 24):
        seconds = EXPOSURE * electrons / 1000.0
        if np.any(np.abs(electrons / switches - 1.0) < 0.1):
            continue
        _, variance = temporal(capture(chain, image, seconds, 4, 0), capture(chain, image, seconds, 4, 1))
        measured = 20 * math.log10(electrons * first.gain_dn_per_e * first.response / math.sqrt(variance))
        assert measured == pytest.approx(20 * math.log10(chain.predicted_snr(electrons, seconds)), abs=0.2), electrons
        checked += 1
    assert checked >= 18


@pytest.mark.parametrize("blend", [0.0, 0.2])
def test_the_merged_signal_is_linear_in_the_light(blend):
    """The merged mean is G_0 DN per reference photo-electron (plus the dark signal) over four decades, across
    every transition, hard or blended: the readouts' estimates agree."""
    chain = replace(SPLIT, merge=replace(SPLIT.merge, blend=blend))
    first = chain.readouts[0]
    dark = first.gain_dn_per_e * first.dark_current_e_s * EXPOSURE
    for electrons in np.geomspace(100.0, 0.9 * chain.saturation_e, 13):
        image = flat_field(chain, float(electrons))[:128, :128]
        merged = green(chain.linear_dn(capture(chain, image, EXPOSURE, 5, 0))).mean()
        signal = electrons * first.gain_dn_per_e * first.response
        assert merged == pytest.approx(signal + dark, rel=0.005), electrons


KNEES = ((0, 0), (2048, 2048), (16384, 2560), (131072, 3072), (2**20 - 1, 4000))


def test_decompanding_gives_the_linear_signal_within_each_segment_step():
    compander = Compander(KNEES, bit_depth=12, black_level_dn=42)
    rng = np.random.default_rng(5)
    linear = np.concatenate(
        [
            np.arange(4096),
            rng.integers(0, 2**20, 200_000),
            [x + d for x, _ in KNEES for d in (-2, -1, 0, 1, 2) if 0 <= x + d < 2**20],
        ]
    )
    codes = compander.compand(linear)
    assert codes.dtype == np.uint16 and codes.min() == 42 and codes.max() == 4042
    error = np.abs(compander.decompand(codes) - linear)
    assert np.all(error <= 0.5 * compander.step(linear) + 1e-9)
    assert np.all(error[:2048] == 0)  # the first segment is the identity


def test_a_companded_chain_decompands_to_its_merged_signal():
    """The same readouts merged, then companded: the image processor's inverse gives the merged codes back
    within half a step of their segment."""
    companded = replace(EXPOSURES, compander=Compander(KNEES))
    image = flat_field(EXPOSURES, 1.0) * np.geomspace(1.0, 3e5, SHAPE[1])[None, :, None]
    merged = capture(EXPOSURES, image, EXPOSURE, 3, 4)
    raw = capture(companded, image, EXPOSURE, 3, 4)
    assert merged.dtype == np.uint32 and raw.dtype == np.uint16 and companded.bit_depth == 12
    error = np.abs(companded.linear_dn(raw) - (merged.astype(np.float64) - EXPOSURES.merge.black_level_dn))
    assert np.all(error <= 0.5 * companded.compander.step(merged) + 1e-9)


def test_the_companded_snr_follows_the_closed_form():
    """Companded, then decompanded: the merged SNR with each segment's rounding Δ²/12 added, within 0.2 dB at
    levels in every segment; where a step is as large as the noise, companding costs more than 0.2 dB, and
    the prediction sees it."""
    chain = replace(EXPOSURES, compander=Compander(KNEES))
    first = chain.readouts[0]
    costs = []
    for electrons in (500.0, 8000.0, 30000.0, 100000.0, 400000.0, 1e6):
        a, b = two_frames(chain, electrons, merged=True)
        _, variance = temporal(chain.linear_dn(a), chain.linear_dn(b))
        measured = 20 * math.log10(electrons * first.gain_dn_per_e / math.sqrt(variance))
        predicted = 20 * math.log10(chain.predicted_snr(electrons, EXPOSURE))
        assert measured == pytest.approx(predicted, abs=0.2), electrons
        costs.append(20 * math.log10(EXPOSURES.predicted_snr(electrons, EXPOSURE)) - predicted)
    assert max(costs) > 0.25 and min(costs) >= 0.0


def test_a_charge_has_its_own_stream():
    """Adding a readout of another photodiode leaves the frames of the others as they were."""
    image = flat_field(SPLIT, 500.0)[:64, :64]
    large = SensorChain(SPLIT.photons, SPLIT.readouts[:2], SPLIT.merge)
    before = capture_readouts(large, image, EXPOSURE, 2, 9)
    after = capture_readouts(SPLIT, image, EXPOSURE, 2, 9)
    assert all(np.array_equal(a, b) for a, b in zip(before, after))
    # the high and the low gain read one charge: the same shot noise, in their ratio of gains
    high, low = (green(f) - r.black_level_dn for f, r in zip(after[:2], SPLIT.readouts))
    assert np.corrcoef(high, low)[0, 1] > 0.9


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(merge=None), r"a sensor of 4 readout\(s\) takes a \[sensor.merge\] table"),
        (
            dict(readouts=SPLIT.readouts[::-1]),
            r"readout 'small-HCG' gives 0.07478 DN per reference photo-electron, not less than readout 'small-LCG'",
        ),
        (
            dict(readouts=(*SPLIT.readouts[:3], replace(SPLIT.readouts[3], dark_current_e_s=1.0))),
            r"readout 'small-LCG': dark_current_e_s = 1.0 differs from the 4.2 of readout 'small-HCG'; both read "
            r"photodiode 'small'",
        ),
        (
            dict(compander=Compander(KNEES)),
            r"compander's last knee must sit at the merged signal's white level \(16777215\)",
        ),
    ],
)
def test_a_chain_that_cannot_be_is_refused_by_name(change, message):
    with pytest.raises(SolasError, match=message):
        replace(SPLIT, **change)


def test_a_merge_too_narrow_for_its_readouts_is_refused():
    """Three exposures 16 × apart span 4031 × 256 DN of the first: 20 bits, not 16."""
    with pytest.raises(
        SolasError,
        match=r"sensor merge bits = 16 holds merged codes up to 65535, below the last "
        r"readout's saturation over black_level_dn \(1032000 in DN of the first "
        r"readout\); give bits >= 20",
    ):
        replace(EXPOSURES, merge=Merge(bits=16))


def test_compander_knees_that_expand_are_refused():
    with pytest.raises(SolasError, match=r"each segment's slope at most 1 and at most the one before"):
        Compander(((0, 0), (100, 50), (1000, 900)))


def test_one_readout_predicts_the_flat_sensors_snr():
    flat = load_sensor("imx490")
    assert chain_of(flat).predicted_snr(1000.0, 0.01) == flat.snr(1000.0, 0.01)


@pytest.mark.parametrize("name", list(CHAINS))
def test_the_dynamic_range_spans_snr_1_to_saturation(name):
    """EMVA 1288's dynamic range: the simulated merged SNR is 1 (0 dB) at μ_e.min within 0.15 dB (measured
    0.01 and 0.02 dB), and the merged signal stops rising at μ_e.sat (the mean at 1.2 × is the saturation code);
    the readouts after the first extend the first's range by more than 10 dB."""
    chain = CHAINS[name]
    floor = chain.saturation_e / 10 ** (chain.dynamic_range_db(EXPOSURE) / 20)
    assert merged_snr_db(chain, floor) == pytest.approx(0.0, abs=0.15)
    top = green(capture(chain, flat_field(chain, 1.2 * chain.saturation_e)[:64, :64], EXPOSURE, 1, 0))
    assert top.mean() - chain.black_level_dn == pytest.approx(chain.saturation_dn, rel=0.01)
    alone = SensorChain(chain.photons, chain.readouts[:1]).dynamic_range_db(EXPOSURE)  # the first readout's
    assert chain.dynamic_range_db(EXPOSURE) > alone + 10.0


@pytest.mark.parametrize("blend", [0.0, 0.2])
def test_frames_worked_in_bands_are_the_frames_worked_whole(monkeypatch, blend):
    """The readouts and the merge work a frame in bands of rows (`readout.bands`, in the processor's cache): a
    band of a row and a half, or of a part of a row, gives the frame of one band over the whole frame."""
    from solas_mi.sensor import readout

    chain = replace(SPLIT, merge=replace(SPLIT.merge, blend=blend))
    rows, cols = np.mgrid[0:37, 0:53]
    image = np.stack([10.0 ** (-3.0 + 6.0 * cols / 52.0) * (1.0 + 0.2 * np.sin(rows))] * 3, axis=-1)
    outputs = {}
    for values in (10**9, 80, 7):
        monkeypatch.setattr(readout, "BAND_VALUES", values)
        readouts = capture_readouts(chain, image, EXPOSURE, 3, 4)
        outputs[values] = [*readouts, capture(chain, image, EXPOSURE, 3, 4)]
    assert len(readout.bands(image.shape[:2])) == 37  # 7 values: a band per row
    for values in (80, 7):
        assert all(np.array_equal(a, b) for a, b in zip(outputs[values], outputs[10**9], strict=True))


def test_charges_drawn_on_threads_give_the_frames_drawn_in_turn(monkeypatch):
    """The charges of a frame are drawn on the process's threads at once, each from its own streams and
    pattern: the readouts are those of the charges drawn one after the other."""
    from solas_mi.sensor import readout

    image = np.full((64, 96, 3), 0.05)
    image[:, 48:] *= 400.0  # past the large photodiode's well: every readout in use
    threaded = capture_readouts(SPLIT, image, EXPOSURE, 5, 6)
    in_turn = []
    monkeypatch.setattr(readout, "in_threads", lambda work, parts: in_turn.extend(work(p) for p in parts))
    readout._PATTERNS.clear()  # drawn again in turn too
    assert all(
        np.array_equal(a, b) for a, b in zip(capture_readouts(SPLIT, image, EXPOSURE, 5, 6), threaded, strict=True)
    )
    assert len(in_turn) == 2  # the two charges, one after the other
