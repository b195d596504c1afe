"""External reference PSFs for the SOLAS doublet, computed with KrakenOS.

Purpose
-------
Produces KrakenOS's Fraunhofer (FFT) PSFs for the SOLAS doublet (object at
infinity) for fields 0, +2, -2 deg along y and wavelengths 486, 531, 656 nm,
sampled on *our* image-plane grid, so that solas-mi's own Fraunhofer PSF code
can be checked against an independent implementation.

Output: ``krakenos_psfs.npz`` + ``README.json`` (default directory
out/kraken_ref, change with ``--out``).  Arrays ``psf_f{+0,+2,-2}_w{486,531,656}``
(physically scaled, see below) and ``native_psf_...`` (KrakenOS's own,
un-tuned EFL/EPD scale).

Installing KrakenOS (side venv, NEVER a dependency of solas-mi)
---------------------------------------------------------------
    python3 -m venv .kraken-venv
    .kraken-venv/bin/pip install krakenos==1.0.0.24 "numpy<2.3" scipy matplotlib
    .kraken-venv/bin/python benchmarks/krakenos_reference.py

(pip pulls pyvista/vtk/pyvtk/pandas as krakenos dependencies; ``import
KrakenOS`` needs them, they install fine from wheels, nothing is stubbed.
KrakenOS's Zernike fit needs NumPy < 2.3.)

What KrakenOS does (1.0.0.24) and what this script overrides
------------------------------------------------------------
* Wavefront: ``Kos.Phase(pupil)`` traces a hexapolar fan of rays aimed at the
  *paraxial* entrance pupil (no real-ray aiming) and returns the OPD, in waves,
  w.r.t. a reference sphere centred on the chief ray's image-plane point and
  passing through the exit-pupil centre, on pupil coordinates normalised by the
  paraxial entrance-pupil radius.  ``Kos.Zernike_Fitting`` fits Noll-normalised
  Zernikes (we use NC = 28, i.e. all terms to radial order 6, the PSFMap
  default) by least squares.
* PSF: ``Kos.psf(COEF, Focal, Diameter, Wave, pixels=N, PupilSample=Q)``
  evaluates the Zernike wavefront on an N x N grid with the unit pupil spanning
  N/Q samples, FFTs ``exp(-2*pi*i*W)`` (zero-padded by Q), returns
  ``rot90(|F|^2)`` normalised so that an unaberrated pupil peaks at 1 (so
  ``max`` ~ Strehl).  The intensity array depends only on COEF, N and Q;
  Focal/Diameter only set the axis labels: image-plane pitch =
  Wave * Focal / (Q * Diameter).
* Tuning factors: ``PSFMap.generate_psf_map`` passes Focal = EFFL and
  Diameter = k * RadPupInp with k = 2.5 (486 nm), 2.80 (531 nm), 3.45 (other),
  "experimentally determined compared OpticStudio".  Since EPD = 2 * RadPupInp,
  this multiplies the pupil diameter by 1.25 / 1.40 / 1.725 and hence shrinks
  the stated pixel pitch by 0.800 / 0.714 / 0.580.  We do NOT use PSFMap (in
  1.0.0.24 it also crashes: with wideAngle=False ``Phase`` receives a pupil
  left in 'rtheta' mode -> one ray -> singular Zernike matrix; with
  wideAngle=True it unpacks ``I, param = Kos.psf(...)`` but ``psf`` returns one
  array).  Instead we call Phase -> Zernike_Fitting -> psf ourselves and set
  the scale from first principles:
    - ``psf_*`` (physical):  Focal = 39.496 mm (exit pupil = stop -> image),
      Diameter = 5.0 mm (stop = exit pupil), i.e. F/7.899;
    - ``native_psf_*`` (KrakenOS un-tuned): Focal = EFFL, Diameter = EPD =
      2 * RadPupInp (k = 2, i.e. tuning factor 1), i.e. F/7.99.
  For each, Q is chosen (non-integer; psf accepts that) so that the FFT pitch
  is exactly 0.25 um.  Our pixel centres, (i - 79.5) * 0.5 um from the chief
  ray, are then exactly FFT samples (odd multiples of 0.25 um), so NO
  interpolation is needed: the 160 x 160 array is a strided subset.
* Glass catalogue: ``Kos.Setup`` loads every .agf in its Cat/ folder in
  ``os.listdir`` order and takes the first name match, so "F2" could resolve
  to CDGM/HOYA/Hikari/Nikon F2 depending on the file system.  We reload the
  catalogue with SCHOTT.AGF only ("BK7" there carries the N-BK7 Sellmeier
  coefficients; "F2" is Schott F2).
* Vignetting: ``PupilCalc`` switches vignetting back on; we call
  ``IgnoreVignetting()`` after it (otherwise 486-nm marginal rays, which land
  at r = 2.5008 mm on the 5.0 mm stop, are dropped from the spot diagram).

Conventions of the delivered arrays (same as solas-mi)
-----------------------------------------------------
160 x 160, pitch 0.5 um, centred on KrakenOS's chief-ray image point: pixel
(row i, col j) is at x = (j - 79.5)*0.5 um, y = (79.5 - i)*0.5 um relative to
it; row 0 = top = largest y, col 0 = smallest x; peak-normalised (max of the
delivered samples = 1).  Field (0, fy) deg = direction of the incoming rays
(KrakenOS ``FieldType='angle'``, same sign as ours: +2 deg images at
y = +3.4745 mm).  The orientation of Kos.psf's output (after its rot90: row
up = +y, column right = +x, chief ray at row N/2-1, column N/2) was verified by
comparing PSF centroids with ray-traced spot centroids for +x and +y fields;
``--checks`` repeats that comparison and stores it in README.json.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

# ----------------------------------------------------------------------------
# Lens (SOLAS paper Table 1).  Surface 4 is the stop (= exit pupil).
# ----------------------------------------------------------------------------
PRESCRIPTION = [  # (Rc [mm], thickness [mm], glass after, clear diameter [mm], name)
    (0.0, 100.0, "AIR", 30.0, "object"),
    (92.847, 6.0, "BK7", 30.0, "L1a"),
    (-30.716, 3.0, "F2", 30.0, "L1b"),
    (-78.197, 57.376, "AIR", 30.0, "L1c"),
    (0.0, 39.496, "AIR", 5.0, "stop"),
    (0.0, 0.0, "AIR", 20.0, "image"),
]
STOP_SURF = 4
STOP_DIAM_MM = 5.0
EXIT_PUPIL_TO_IMAGE_MM = 39.496

WAVES_UM = (0.486, 0.531, 0.656)
FIELDS_Y_DEG = (0.0, 2.0, -2.0)

NPIX_OUT = 160
PITCH_OUT_UM = 0.5
FFT_PITCH_UM = 0.25  # = PITCH_OUT_UM / 2 -> our pixel centres are FFT samples
N_FFT = 2560  # FFT size; the unit pupil spans N_FFT/Q = 122..167 samples
N_ZERNIKE = 28  # KrakenOS PSFMap default (radial orders 0..6)
PUPIL_RINGS = 20  # hexapolar rings for Kos.Phase -> 1261 rays

TUNING_K = {0.486: 2.5, 0.531: 2.80, 0.656: 3.45}  # PSFMap: Diameter = k*RadPupInp


def case_key(fy: float, w_um: float) -> str:
    return f"f{int(round(fy)):+d}_w{int(round(w_um * 1000))}"


def build_lens(Kos):
    surfs = []
    for rc, t, glass, dia, name in PRESCRIPTION:
        s = Kos.surf()
        s.Rc, s.Thickness, s.Glass, s.Diameter, s.Name = rc, t, glass, dia, name
        surfs.append(s)
    cfg = Kos.Setup()
    from KrakenOS.SetupClass import rute  # KrakenOS's catalogue folder

    cfg.GlassCat = [rute + "SCHOTT.AGF"]  # force Schott N-BK7 ("BK7") and Schott F2
    cfg.Load(cfg.GlassCat)
    return Kos.system(surfs, cfg)


def make_pupil(Kos, lens, w_um, fy, ptype, samp):
    pup = Kos.PupilCalc(lens, STOP_SURF, w_um, "STOP", STOP_DIAM_MM)
    lens.IgnoreVignetting()  # PupilCalc re-enables vignetting
    pup.FieldType = "angle"
    pup.FieldX, pup.FieldY = 0.0, fy
    pup.Ptype, pup.Samp = ptype, samp
    return pup


def trace_bundle(lens, pup, w_um):
    x, y, z, L, M, N = pup.Pattern2Field()
    pts = []
    for i in range(len(x)):
        lens.Trace([x[i], y[i], z[i]], [L[i], M[i], N[i]], w_um)
        pts.append(lens.XYZ[-1][:2])
    return np.asarray(pts)


def chief_ray_point(Kos, lens, w_um, fy):
    pup = make_pupil(Kos, lens, w_um, fy, "chief", 1)
    return trace_bundle(lens, pup, w_um)[0]  # (x, y) mm on the image plane


def spot_stats(Kos, lens, w_um, fy, ptype="square", samp=40):
    pup = make_pupil(Kos, lens, w_um, fy, ptype, samp)
    p = trace_bundle(lens, pup, w_um)
    c = p.mean(axis=0)
    rms = np.sqrt(np.mean(np.sum((p - c) ** 2, axis=1)))
    return rms * 1e3, c, len(p)


def zernike_wavefront(Kos, lens, w_um, fy):
    pup = make_pupil(Kos, lens, w_um, fy, "hexapolar", PUPIL_RINGS)
    X, Y, Z, p2v = Kos.Phase(pup)
    coef, _, _rms_chief, rms_centroid, fit_err = Kos.Zernike_Fitting(X, Y, Z, np.ones(N_ZERNIKE))
    info = dict(
        p2v_waves=float(p2v),
        rms_wfe_waves_fit=float(rms_centroid),
        zernike_fit_rms_residual_waves=float(fit_err),
        n_pupil_rays=int(len(X)),
        EFFL_mm=float(pup.EFFL),
        EPD_mm=float(2 * pup.RadPupInp),
        entrance_pupil_z_from_surface0_mm=float(pup.PosPupInp[2]),
        exit_pupil_z_from_image_mm=float(pup.PosPupOutFoc[2]),
    )
    return np.asarray(coef, float), pup, info


def kraken_psf(Kos, coef, w_um, focal_mm, diam_mm, npix=N_FFT, pitch_um=FFT_PITCH_UM):
    """Kos.psf with Q chosen so its pitch w*focal/(Q*diam) equals pitch_um."""
    q = w_um * focal_mm / (diam_mm * pitch_um)
    img = Kos.psf(coef, focal_mm, diam_mm, w_um, pixels=npix, PupilSample=q)
    return np.asarray(img, float), q


def to_our_grid(img):
    """Strided subset: our pixel i sits at (2i-159) FFT samples from the chief ray.

    Kos.psf output: chief ray (zero spatial frequency) at row N/2-1, col N/2
    (fftshift puts it at N/2, rot90 maps (N/2, N/2) -> (N/2-1, N/2)); row
    index increasing = -y, column index increasing = +x (verified).
    """
    n = img.shape[0]
    r0, c0 = n // 2 - 1, n // 2
    h = NPIX_OUT - 1  # 159
    out = img[r0 - h : r0 + h + 1 : 2, c0 - h : c0 + h + 1 : 2]
    assert out.shape == (NPIX_OUT, NPIX_OUT)
    return out


def centroid_offset_um(img, pitch_um):
    n = img.shape[0]
    r, c = np.indices(img.shape)
    s = img.sum()
    dx = ((c * img).sum() / s - n // 2) * pitch_um
    dy = -((r * img).sum() / s - (n // 2 - 1)) * pitch_um
    return float(dx), float(dy)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="out/kraken_ref")
    ap.add_argument("--no-checks", action="store_true", help="skip spot-RMS / centroid checks")
    ap.add_argument(
        "--map-timing", action="store_true", help="also time an 8x8 field map at PSFMap defaults (144 px, Q=4)"
    )
    args = ap.parse_args()

    import KrakenOS as Kos

    os.makedirs(args.out, exist_ok=True)
    lens = build_lens(Kos)

    # perfect-pupil check of the chief-ray pixel for this FFT size
    z0 = np.zeros(N_ZERNIKE)
    z0[0] = 1e-9  # Kos.psf fails on an all-zero COEF (wavefront becomes a scalar)
    perf, _ = kraken_psf(Kos, z0, 0.531, 100.0, 12.5, npix=256, pitch_um=1.0)
    assert np.unravel_index(np.argmax(perf), perf.shape) == (127, 128)

    arrays, cases, timing = {}, {}, {}
    t_all = time.perf_counter()
    for w in WAVES_UM:
        for fy in FIELDS_Y_DEG:
            key = case_key(fy, w)
            t0 = time.perf_counter()
            coef, pup, info = zernike_wavefront(Kos, lens, w, fy)
            t1 = time.perf_counter()
            img_phys, q_phys = kraken_psf(Kos, coef, w, EXIT_PUPIL_TO_IMAGE_MM, STOP_DIAM_MM)
            t2 = time.perf_counter()
            img_nat, q_nat = kraken_psf(Kos, coef, w, pup.EFFL, 2 * pup.RadPupInp)
            t3 = time.perf_counter()
            chief = chief_ray_point(Kos, lens, w, fy)

            for prefix, img in (("psf", img_phys), ("native_psf", img_nat)):
                sub = to_our_grid(img)
                arrays[f"{prefix}_{key}"] = (sub / sub.max()).astype(np.float64)

            # refractive indices actually used by KrakenOS
            lens.Trace([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], w)
            n_used = [float(v) for v in lens.N0[1:3]]

            c = dict(
                field_y_deg=fy,
                wavelength_nm=round(w * 1000),
                chief_ray_image_xy_mm=[float(chief[0]), float(chief[1])],
                n_BK7=n_used[0],
                n_F2=n_used[1],
                zernike_noll_waves=[float(v) for v in coef],
                strehl_kraken_phys_grid=float(img_phys.max()),
                strehl_kraken_native_grid=float(img_nat.max()),
                Q_phys=float(q_phys),
                Q_native=float(q_nat),
                pupil_samples_across_phys=float(N_FFT / q_phys),
                pupil_samples_across_native=float(N_FFT / q_nat),
                native_F_number_EFL_over_EPD=float(pup.EFFL / (2 * pup.RadPupInp)),
                psfmap_tuned_pitch_factor=2.0 / TUNING_K[w],
                time_s=dict(phase_and_zernike=t1 - t0, psf_fft_phys=t2 - t1, psf_fft_native=t3 - t2),
                **info,
            )
            if not args.no_checks:
                rms_um, cen, nray = spot_stats(Kos, lens, w, fy)
                rms_hex, _, _nhex = spot_stats(Kos, lens, w, fy, "hexapolar", 20)
                c["spot_rms_um_uniform_square_grid"] = float(rms_um)
                c["spot_rms_um_hexapolar20"] = float(rms_hex)
                c["spot_n_rays"] = int(nray)
                geo = ((cen - chief) * 1e3).tolist()
                c["geometric_centroid_minus_chief_um"] = geo
                c["fft_psf_centroid_minus_chief_um_phys"] = centroid_offset_um(img_phys, FFT_PITCH_UM)
                c["fft_psf_centroid_minus_chief_um_native"] = centroid_offset_um(img_nat, FFT_PITCH_UM)
            cases[key] = c
            timing[key] = t3 - t0
            print(f"{key}: chief y={chief[1]:+.6f} mm  Strehl={img_phys.max():.4f}  {t3 - t0:.2f} s", flush=True)
    t_total = time.perf_counter() - t_all

    map_timing = None
    if args.map_timing:
        # 8x8 fields, PSFMap defaults: 144 px, Q=4, NC=28, Phase with 3 hexapolar rings
        # would be under-determined for 28 terms, so use PUPIL_RINGS as above.
        fx = np.linspace(-2, 2, 8)
        t0 = time.perf_counter()
        for a in fx:
            for b in fx:
                pup = Kos.PupilCalc(lens, STOP_SURF, 0.531, "STOP", STOP_DIAM_MM)
                pup.FieldType, pup.FieldX, pup.FieldY = "angle", float(a), float(b)
                pup.Ptype, pup.Samp = "hexapolar", PUPIL_RINGS
                X, Y, Z, _ = Kos.Phase(pup)
                coef = Kos.Zernike_Fitting(X, Y, Z, np.ones(N_ZERNIKE))[0]
                Kos.psf(coef, pup.EFFL, 2 * pup.RadPupInp, 0.531, pixels=144, PupilSample=4)
        map_timing = time.perf_counter() - t0
        print(f"8x8 map (531 nm, 144 px, Q=4): {map_timing:.1f} s", flush=True)

    np.savez(os.path.join(args.out, "krakenos_psfs.npz"), **arrays)

    readme = dict(
        source="KrakenOS 1.0.0.24 (PyPI krakenos), Kos.Phase -> Kos.Zernike_Fitting -> Kos.psf; "
        "generated by solas-mi benchmarks/krakenos_reference.py",
        lens="SOLAS doublet, paper Table 1; Schott catalogue only (BK7 = N-BK7 coefficients, F2 = Schott F2); "
        "stop (surface 4, dia 5.0 mm) = exit pupil, 39.496 mm before the image plane",
        arrays=dict(
            names="psf_f{+0,+2,-2}_w{486,531,656} (physical scale) and native_psf_... (KrakenOS un-tuned EFL/EPD scale)",
            shape=[NPIX_OUT, NPIX_OUT],
            dtype="float64",
            pixel_pitch_um=PITCH_OUT_UM,
            centre="chief ray's intersection with the image plane (KrakenOS chief ray, aimed at the paraxial "
            "entrance-pupil centre); coordinates in cases[*].chief_ray_image_xy_mm",
            pixel_coordinates="pixel (row i, col j) centre at x = (j - 79.5)*0.5 um, y = (79.5 - i)*0.5 um "
            "relative to the chief-ray point; no sample lies on the chief ray itself",
            orientation="row 0 = top = largest image y; column 0 = left = smallest image x",
            normalisation="peak-normalised: max of the delivered 160x160 samples = 1 "
            "(KrakenOS's own Strehl-normalised peak is in cases[*].strehl_kraken_*)",
            resampling="none: Kos.psf run with Q = lambda*F/(D*0.25 um) so the FFT pitch is exactly 0.25 um; "
            "our 0.5-um pixel centres are odd multiples of 0.25 um from the chief ray, i.e. exact "
            "FFT samples (strided subset, no interpolation)",
            physical_scale="psf_*: F = R/D_exit = 39.496/5.0 = 7.8992 (exit pupil = stop); FFT pitch = "
            "lambda*R/(Q*D_exit); axial R used for all fields (off-axis obliquity, chief-ray angle "
            "5.0 deg in image space, would stretch y by 1/cos^3 = 1.0116 and x by 1/cos = 1.0039; "
            "not applied)",
            native_scale="native_psf_*: KrakenOS's formula pitch = lambda*Focal/(Q*Diameter) with Focal = EFFL, "
            "Diameter = EPD = 2*RadPupInp (PSFMap tuning factor removed, i.e. k = 2 instead of "
            "2.5/2.80/3.45), F = EFL/EPD ~ 7.99",
            intensity="|FFT|^2 of the 28-term Zernike-fitted pupil function (uniform amplitude), "
            "pupil sampled on the FFT grid with the unit circle spanning N/Q samples",
        ),
        conventions=dict(
            field="field (0, fy) deg = direction of the incoming collimated rays (KrakenOS FieldType='angle'); "
            "+2 deg in y images at y = +3.4745 mm at 531 nm (same as solas-mi)",
            wavelength_um=list(WAVES_UM),
        ),
        kraken_settings=dict(
            pupil=f"Kos.Phase on a hexapolar pattern, {PUPIL_RINGS} rings ({1 + 3 * PUPIL_RINGS * (PUPIL_RINGS + 1)} "
            "rays), rays aimed at the paraxial entrance pupil",
            n_zernike=N_ZERNIKE,
            zernike="Noll-normalised, Noll order, least squares",
            fft_size=N_FFT,
            fft_pitch_um=FFT_PITCH_UM,
            wavefront_reference="sphere centred on the chief ray's image-plane point through the exit-pupil centre",
            psfmap_tuning_factors_removed=dict(
                code="PSFMap.generate_psf_map: Diameter = k*RadPupInp, k = 2.5 (486), 2.80 (531), 3.45 (else)",
                effect="stated pitch multiplied by 2/k = 0.800 / 0.714 / 0.580",
            ),
        ),
        notes=[
            "Spot RMS: uniform (area-weighted) pupil sampling gives 20.09/19.37/23.87 um on axis and "
            "8.26/7.89/10.16 um at +-2 deg (486/531/656); the equal-weight 20-ring hexapolar pattern gives "
            "20.60/19.83/24.39 and 8.58/8.06/10.37 um, i.e. the commonly quoted numbers use hexapolar weighting.",
            "Centroid check: PSF centroid minus chief ray vs ray-traced spot centroid (uniform sampling) agree to "
            "0.9-3% (physical scale) / 0-1.6% (native scale); residual from obliquity and pupil distortion, which "
            "an FFT PSF on paraxial entrance-pupil coordinates ignores.",
            "KrakenOS PSFMap.generate_psf_map is unusable in 1.0.0.24 (singular Zernike fit with wideAngle=False, "
            "unpack error with wideAngle=True); the 8x8 map timing is for the equivalent Phase/fit/psf loop.",
            "KrakenOS PupilCalc.RadPupOut is wrong for this lens (~1.0 mm instead of 2.5 mm); it is not used by "
            "the PSF (only as a surface diameter with vignetting ignored).",
        ],
        timing_s=dict(per_case=timing, total_9_cases=t_total, map_8x8_531nm_144px_Q4=map_timing),
        cases=cases,
    )
    with open(os.path.join(args.out, "README.json"), "w") as f:
        json.dump(readme, f, indent=1, allow_nan=False)  # strict JSON: no NaN/Infinity tokens
    print("wrote", os.path.join(args.out, "krakenos_psfs.npz"), f"in {t_total:.1f} s")


if __name__ == "__main__":
    main()
