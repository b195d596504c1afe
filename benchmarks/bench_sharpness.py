"""The e-SFR MTF50 of a degraded slanted edge beside the lens's MTF50 × the pixel's MTF, per shipped lens.

For each lens, at 0.7 of its half field and its primary wavelength: the slanted edge (5 deg from the
pixel columns, its normal along x: sagittal; or from the rows, normal along y: tangential) is drawn at
8 × 8 samples per pixel, convolved with the lens's Fraunhofer PSF there (`psf.psf`, sampled at the
same 1/8 px), integrated over square pixels of 100 % fill and measured by ISO 12233 e-SFR
(`metrics.esfr`, sfrmat5's 2023 mode); beside it, the MTF50 of the lens's diffraction MTF at that field
(`analysis.mtf.lens_otf`) times the pixel's (|sinc|, along the edge normal) and the 1/8-px ramp the edge
is drawn with (|sinc(f/8)|). The pixel pitch is chosen per lens so that the lens's MTF50 in its sharper
direction falls at 0.3 cy/px (blur wide enough to sample, narrow enough for the e-SFR's ROI, and below
Nyquist). The three
lenses with the largest off-axis blur (the lowest lens MTF50 in cycles/mm at that field) are the
acceptance set: within 3 %.

e-SFR measures the MTF along the edge's normal, 5 deg off the axis: beside the lens's MTF along the axis, its
MTF along that normal (`normal_mtf50`, from the Fraunhofer PSF), which on the fisheye's sagittal edge is
2.4 % lower (its tangential blur is 3x the sagittal).

On those three lenses the same edges are also rendered through the lens in Mitsuba and measured by e-SFR
(`rendered_edge`: a short crop at the field, flat-fielded, two seeds), beside the same predictions (with
the object's texel ramp in place of the drawing ramp) and the e-SFR of the crop built from the geometric
spots (what the render traces) of the edge's points along it (`rendered_edge.geometric_crop`).

    .venv/bin/python benchmarks/bench_sharpness.py              # or: benchmarks/run_all.py bench_sharpness
"""

from __future__ import annotations

import math
import re
import sys

import numpy as np

FIELD_FRACTION = 0.7
OVERSAMPLE = 8  # samples per pixel side
ROI_PX = 240  # the measured region, pixels a side
TILT_DEG = 5.0
LENS_MTF50_CY_PX = 0.3  # where the pitch puts the lens's tangential MTF50
ACCEPTANCE = 0.03
LENSES = 3  # the lenses of largest off-axis blur the acceptance holds for
MAX_PUPIL = 2048


def edge_image(psf_data: np.ndarray, normal: str) -> np.ndarray:
    """ROI_PX² pixels: a step (0.2 to 0.8) tilted TILT_DEG from the columns (normal "x") or rows ("y"),
    OVERSAMPLE² samples a pixel, each sample the step's covered fraction on a 1-sample ramp, convolved
    with `psf_data` (rows: +y first, sampled at 1/OVERSAMPLE px) and integrated over each pixel."""
    margin = psf_data.shape[0] // OVERSAMPLE + 4
    side = (ROI_PX + 2 * margin) * OVERSAMPLE
    c = np.arange(side) - (side - 1) / 2
    x, y = np.meshgrid(c, -c)  # image orientation: row 0 at the top
    t = math.radians(TILT_DEG)
    distance = x * math.cos(t) + y * math.sin(t) if normal == "x" else y * math.cos(t) - x * math.sin(t)
    fine = 0.2 + 0.6 * np.clip(0.5 + distance, 0.0, 1.0)
    kernel = np.zeros_like(fine)
    k = psf_data / psf_data.sum()
    h = k.shape[0]
    kernel[:h, :h] = k
    kernel = np.roll(kernel, (-(h // 2), -(h // 2)), axis=(0, 1))
    blurred = np.real(np.fft.ifft2(np.fft.fft2(fine) * np.fft.fft2(kernel)))
    pixels = blurred.reshape(side // OVERSAMPLE, OVERSAMPLE, side // OVERSAMPLE, OVERSAMPLE).mean(axis=(1, 3))
    return pixels[margin:-margin, margin:-margin]


def predicted(
    lens,
    field: float | tuple[float, ...],
    wavelength: float,
    pitch_um: float,
    direction: int,
    ramp_px: float = 1.0 / OVERSAMPLE,
) -> tuple[float, float]:
    """(lens MTF50 in cy/mm, MTF50 of lens × pixel × the edge's drawing ramp of `ramp_px` pixels, in cy/px)
    along the direction (0: y, tangential; 1: x, sagittal) at field (0, `field`) deg; a tuple of fields:
    of the mean of their lens MTFs."""
    from solas_mi.analysis.inputs import cutoff_cy_mm
    from solas_mi.analysis.mtf import lens_otf
    from solas_mi.metrics.mtf import mtf50

    fields = field if isinstance(field, tuple) else (field,)
    freq = np.linspace(0.0, cutoff_cy_mm(lens, wavelength), 4001)
    lens_mtf = np.abs(lens_otf(lens, fields, (wavelength,), (1.0,), freq, None)[0][:, direction]).mean(axis=0)
    f_px = freq * pitch_um * 1e-3
    return mtf50(lens_mtf, freq), mtf50(lens_mtf * pixel_mtf(f_px, ramp_px), f_px)


def normal_mtf50(psf, pitch_um: float, direction: int, ramp_px: float = 1.0 / OVERSAMPLE) -> float:
    """MTF50 (cy/px) of the lens's MTF along the slanted edge's normal (TILT_DEG from y for the tangential
    edge, direction 0, from x for the sagittal, 1), the Fourier transform of its Fraunhofer PSF `psf`
    (`lens_psf`, sampled at pitch_um/OVERSAMPLE) projected on that normal, × the pixel's and the ramp's
    (`pixel_mtf`): what e-SFR measures, where `predicted` takes the MTF along the axis. On the fisheye at
    63° the sagittal edge's 5° mixes in enough of the 3× wider tangential blur to lower it 2.4 %."""
    from solas_mi.analysis.otf import spot_otf
    from solas_mi.metrics.mtf import mtf50

    n = psf.data.shape[0]
    c = (np.arange(n) - n // 2) * pitch_um * 1e-3 / OVERSAMPLE
    x, y = np.meshgrid(c, -c)  # rows: +y first
    a = math.radians(TILT_DEG + (90.0 if direction == 0 else 0.0))
    f_px = np.linspace(0.0, 1.0, 501)
    otf = spot_otf((x * math.cos(a) + y * math.sin(a)).ravel(), psf.data.ravel(), f_px / (pitch_um * 1e-3))
    return mtf50(np.abs(otf) * pixel_mtf(f_px, ramp_px), f_px)


def pixel_mtf(f_px: np.ndarray, ramp_px: float) -> np.ndarray:
    """The MTF along an edge's normal (TILT_DEG from the pixel axis) of a square pixel of 100 % fill and of
    the ramp of `ramp_px` pixels the edge is drawn with, at `f_px` cycles/pixel."""
    t = math.radians(TILT_DEG)
    return np.abs(np.sinc(f_px * math.cos(t)) * np.sinc(f_px * math.sin(t)) * np.sinc(f_px * ramp_px))


def lens_psf(lens, field: float, wavelength: float, pitch_um: float):
    """The Fraunhofer PSF at `field`, sampled at `pitch_um`, in a window of 2.5 spot diameters (at least 64
    samples), on a pupil grid fine enough that its period (about N lambda N) is 1.3 windows and its phase
    steps are resolved (more samples, up to MAX_PUPIL, where the PSF method asks for them)."""
    from solas_mi.optics.paraxial import paraxial
    from solas_mi.optics.spot import spot
    from solas_mi.psf import psf

    s = spot(lens, (0.0, field), wavelength)
    size = max(64, int(2.5 * 2 * np.hypot(s.x_um, s.y_um).max() / pitch_um) // 2 * 2)
    period = wavelength * 1e-3 * paraxial(lens, wavelength).working_f_number
    samples = min(MAX_PUPIL, max(256, int(math.ceil(1.3 * size * pitch_um / period / 8)) * 8))
    while True:
        p = psf(lens, (0.0, field), wavelength, pitch_um=pitch_um, size=size, pupil_samples=samples)
        asked = [int(m) for w in p.meta["warnings"] for m in re.findall(r"--pupil-samples (\d+)", w)]
        if not asked or samples >= MAX_PUPIL:
            return p, samples
        samples = min(MAX_PUPIL, max(asked))


def measure(lens) -> list[dict]:
    """Both directions of one lens (module docstring)."""
    from solas_mi.metrics.esfr import esfr

    wl = lens.primary_wavelength
    field = FIELD_FRACTION * lens.field_deg
    sharpest = max(predicted(lens, field, wl, 1000.0, d)[0] for d in (0, 1))
    pitch = 1000.0 * LENS_MTF50_CY_PX / sharpest
    p, samples = lens_psf(lens, field, wl, pitch / OVERSAMPLE)
    rows = []
    for direction, normal in ((0, "y"), (1, "x")):
        lens_mtf50, expected = predicted(lens, field, wl, pitch, direction)
        found = esfr(edge_image(p.data, normal))
        rows.append(
            {
                "lens": lens.name,
                "field": field,
                "pitch": pitch,
                "direction": ("tangential", "sagittal")[direction],
                "lens_cy_mm": lens_mtf50,
                "expected": expected,
                "normal": normal_mtf50(p, pitch, direction),
                "esfr": found.mtf50,
                "valid": found.valid,
                "reason": found.reason,
                "energy": p.meta["energy_in_grid"],
                "samples": samples,
            }
        )
    return rows


def main() -> int:
    from solas_mi import Lens
    from solas_mi.optics.formats import shipped_lenses

    rows = [r for name in shipped_lenses() for r in measure(Lens.load(name))]
    blur = sorted({r["lens"] for r in rows}, key=lambda n: min(r["lens_cy_mm"] for r in rows if r["lens"] == n))
    chosen = set(blur[:LENSES])
    print(
        f"e-SFR MTF50 of a slanted edge ({TILT_DEG:g} deg) degraded by the lens's PSF at {FIELD_FRACTION:g} of its half "
        "field (primary wavelength) and integrated over square pixels, beside the MTF50 of the lens's diffraction MTF "
        "x the pixel's; the three lenses of largest off-axis blur (lowest lens MTF50) marked *:"
    )
    print()
    print(
        "| lens | field (deg) | pixel (um) | direction | lens MTF50 (cy/mm) | lens x pixel MTF50 (cy/px) | "
        "e-SFR MTF50 (cy/px) | difference | lens x pixel MTF50 along the edge normal (cy/px) | difference |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    worst = 0.0
    for r in rows:
        diff = (r["esfr"] - r["expected"]) / r["expected"] if r["esfr"] is not None else math.nan
        mark = " *" if r["lens"] in chosen else ""
        if r["lens"] in chosen:
            worst = max(worst, abs(diff))
        print(
            f"| {r['lens']}{mark} | {r['field']:.3g} | {r['pitch']:.3g} | {r['direction']} | {r['lens_cy_mm']:.4g} | "
            f"{r['expected']:.4f} | {r['esfr']:.4f} | {100 * diff:+.2f} % | {r['normal']:.4f} | "
            f"{100 * (r['esfr'] / r['normal'] - 1):+.2f} % |"
        )
    print()
    print(
        f"Largest difference on the three lenses of largest off-axis blur ({', '.join(sorted(chosen))}): "
        f"{100 * worst:.2f} % (acceptance {100 * ACCEPTANCE:g} %): {'met' if worst <= ACCEPTANCE else 'NOT met'}."
    )
    print()
    print_rendered([r for r in rows if r["lens"] in chosen and r["direction"] == "tangential"])
    return 0


def print_rendered(chosen: list[dict]) -> None:
    """The rendered route (`rendered_edge`) on the lenses of `chosen` (one row each: lens, field, pitch)."""
    from figures import figure
    from rendered_edge import ALONG_PX, RINGS, ROI_PX, SEEDS, SPP, TEXELS_PER_PX, measure_rendered

    from solas_mi import Lens

    rows = [
        r
        for c in chosen
        for r in measure_rendered(Lens.load(c["lens"]), c["field"], Lens.load(c["lens"]).primary_wavelength, c["pitch"])
    ]
    print(
        f"The same edges rendered through the lens in Mitsuba ({RINGS}-ring cap meshes, {ROI_PX}x{ALONG_PX}-px crop at the "
        f"field, {SPP} spp, seeds {', '.join(map(str, SEEDS))}, object texels 1/{TEXELS_PER_PX} px, the edge tilted {TILT_DEG:g} deg in "
        "the image, flat-fielded by a render of a uniform object), beside the lens x pixel x texel MTF50 along the "
        "axis and along the edge's normal (what e-SFR measures; the acceptance), the e-SFR of the crop built from "
        "the geometric spots (what the render traces) of the edge's points, and the normal's prediction x that crop's "
        "e-SFR / the same crop's at the one field (the crop's field spread as e-SFR merges it):"
    )
    print()
    print(
        "| lens | direction | lens x pixel x texel MTF50 along the axis (cy/px) | along the edge normal | "
        "rendered e-SFR MTF50 (cy/px, mean of seeds) | seeds' spread | difference from the normal's | "
        "difference from the axis's | geometric crop's e-SFR MTF50 (its fields) | over the crop | "
        "difference from it | measured tilt (deg) | "
        "render time per edge (s) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    worst = over_crop = 0.0
    for r in rows:
        diff = (r["esfr"] - r["normal"]) / r["normal"]
        worst = max(worst, abs(diff)) if math.isfinite(diff) else math.inf
        over_crop = max(over_crop, abs(r["esfr"] / r["crop"] - 1.0)) if math.isfinite(diff) else math.inf
        print(
            f"| {r['lens']} | {r['direction']} | {r['expected']:.4f} | {r['normal']:.4f} | {r['esfr']:.4f} | "
            f"{100 * r['spread'] / r['normal']:.2f} % | {100 * diff:+.2f} % | {100 * (r['esfr'] / r['expected'] - 1):+.2f} % | "
            f"{r['rows']:.4f} ({r['fields'][0]:.3g}-{r['fields'][1]:.3g} deg) | {r['crop']:.4f} | "
            f"{100 * (r['esfr'] / r['crop'] - 1):+.2f} % | {r['tilt']:.2f} | {r['seconds']:.0f} |"
            + (f" {r['reason']}" if r["reason"] else "")
        )
    print()
    print(
        f"Largest difference of the rendered edges from the lens x pixel MTF50 along the edge normal: {100 * worst:.2f} % "
        f"(acceptance {100 * ACCEPTANCE:g} %): {'met' if worst <= ACCEPTANCE else 'NOT met'}; from the prediction over "
        f"the crop (its field spread as e-SFR reads it): {100 * over_crop:.2f} %."
    )
    print()
    figure("rendered_edges_s", sum(r["seconds"] for r in rows), "s")


if __name__ == "__main__":
    sys.exit(main())
