"""`sellmeier_dielectric` (BSDF): a smooth dielectric interface between two catalogue (or model)
glasses, the index evaluated per path at its wavelength (`solas_mi.optics.glass`: the catalogue's
Sellmeier formula, or a model glass's two-term fit).

| parameter   | type   | unit | default    | meaning                                              |
|-------------|--------|------|------------|------------------------------------------------------|
| `int_glass` | string | —    | "AIR"      | glass on the side opposite the normal (the interior) |
| `ext_glass` | string | —    | "AIR"      | glass on the normal's side                           |
| `fresnel`   | string | —    | "transmit" | Fresnel losses: "transmit", "sample" or "off"        |
| `wavelength`| float  | nm   | 587.5618   | the wavelength of the non-spectral (mono) variants   |
| `temperature_c` | float | °C | 20        | the glasses' temperature (`Lens.at`: the Schott formula) |
| `pressure_kpa` | float | kPa | 101.325   | the air's pressure; indices are relative to that air |

Glass names are those of lens files: "N-BK7", "SCHOTT:F2", "OHARA:S-LAH59", "model:1.5168/64.17", "AIR"
(a bare name that two vendors use, such as "F2", is refused).
`traverse` exposes nothing: no parameter is differentiable or editable through `mi.traverse`.

The reflectance R is the unpolarised Fresnel reflectance of a dielectric interface, the mean of the
s and p terms (M. Born, E. Wolf, "Principles of Optics", 7th ed., Cambridge University Press, 1999,
§1.5.2), evaluated by Mitsuba's `fresnel`:
- "transmit" (default): refract with weight 1 − R, the Fresnel transmittance (no ghost paths, no
  noise from choosing between reflection and refraction);
- "sample": reflect with probability R, as a real interface does, so ghost images appear;
- "off": refract with weight one, the sequential tracer's radiometry.
Total internal reflection reflects in every mode. Radiance crossing from index n₁ into n₂ is scaled
by (n₂/n₁)², importance is not (E. Veach, "Robust Monte Carlo Methods for Light Transport
Simulation", PhD thesis, Stanford University, 1997, ch. 5).

Components (`BSDFContext.component`, `type_mask`): 0 is the reflection, 1 the transmission. A request
for one of them alone returns it every time with its own weight, as Mitsuba's `dielectric` does:
reflection R (1 under total internal reflection; with "off", 1 only there), transmission 1 − R
(with "off", 1; 0 under total internal reflection), radiance transmission times (n₂/n₁)².

Wavelengths: a mono variant carries none; the index is taken at `wavelength` (default the helium d
line), which solas-mi's scenes set to the camera response's one wavelength (`solas_mi.render.scene`).
In the spectral variants `wavelength` is unused: solas-mi's sensors carry one wavelength (nm) in all
four spectral lanes, and lane 0's index serves all four. A stock camera (`perspective`, …) carries four different wavelengths that
refract into four directions. The interface then follows one lane, chosen uniformly from `sample1`,
and weighs it by 4 and the others by 0 (pbrt-v4's `SampledWavelengths::TerminateSecondary`, made
per interface: M. Pharr, W. Jakob, G. Humphreys, "Physically Based Rendering", 4th ed., MIT Press,
2023). Each lane's expected contribution is exact after any number of interfaces; a path
through k interfaces survives in one of its lanes with probability 4^(1−k), so stock-camera renders
through glass are noisier than the same render through solas-mi's sensors. (Terminating once per
path, as pbrt-v4 does, needs the path's state: Mitsuba gives a BSDF none — writing `si.wavelengths`
does not reach the next ray — and scaling lane 0 by 4 at every interface comes out 4^(k−1) too
bright.)
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
from solas_mi.plugins.wavelength_sampling import mono_wavelength

from solas_mi.errors import SolasError
from solas_mi.optics import thermal
from solas_mi.optics.glass import resolve
from solas_mi.render.spec import FRESNEL_MODES


class SellmeierDielectric(mi.BSDF):
    """The `sellmeier_dielectric` BSDF (parameters: the module docstring)."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        where = thermal.check_environment(
            props.get("temperature_c", thermal.STANDARD_C), props.get("pressure_kpa", thermal.STANDARD_KPA)
        )
        self.int_glass = resolve(props.get("int_glass", "AIR")).at(*where)
        self.ext_glass = resolve(props.get("ext_glass", "AIR")).at(*where)
        self.fresnel = str(props.get("fresnel", "transmit"))
        if self.fresnel not in FRESNEL_MODES:
            raise SolasError(f"sellmeier_dielectric fresnel {self.fresnel!r} must be one of {', '.join(FRESNEL_MODES)}")
        self.wavelength = mono_wavelength(props, "sellmeier_dielectric")
        reflection = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        transmission = mi.BSDFFlags.DeltaTransmission | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        self.m_components = [reflection, transmission]
        self.m_flags = reflection | transmission

    def eta(self, wavelength) -> mi.Float:
        """n_int / n_ext at `wavelength` (nm; the `wavelength` parameter in the non-spectral variants)."""
        um = mi.Float(wavelength if mi.is_spectral else self.wavelength) * 1e-3
        return self.int_glass.index_formula(um, dr.sqrt) / self.ext_glass.index_formula(um, dr.sqrt)

    def sample(self, ctx, si, sample1, sample2, active=True):
        has_r = ctx.is_enabled(mi.BSDFFlags.DeltaReflection, 0)
        has_t = ctx.is_enabled(mi.BSDFFlags.DeltaTransmission, 1)
        lam, lane, sample1, mixed = self._lane(si.wavelengths, sample1)
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        r_i, cos_theta_t, eta_it, eta_ti = mi.fresnel(cos_theta_i, self.eta(lam))
        tir = r_i >= 1.0
        if self.fresnel == "off":
            r_w, t_w = dr.select(tir, 1.0, 0.0), dr.select(tir, 0.0, 1.0)
        else:
            r_w, t_w = self.split(r_i, tir, cos_theta_i, lam)
        if has_r and has_t:
            reflect = (sample1 <= r_w) if self.fresnel == "sample" else tir
            scale = dr.select(reflect, 1.0, self.sampled_transmission(r_w, t_w) if self.fresnel == "sample" else t_w)
        else:
            reflect = mi.Bool(has_r)
            scale = r_w if has_r else t_w
        bs = mi.BSDFSample3f()
        bs.wo = dr.select(reflect, mi.reflect(si.wi), mi.refract(si.wi, cos_theta_t, eta_ti))
        bs.pdf = 1.0
        bs.eta = dr.select(reflect, 1.0, eta_it)
        bs.sampled_component = dr.select(reflect, mi.UInt32(0), mi.UInt32(1))
        bs.sampled_type = dr.select(
            reflect, mi.UInt32(+mi.BSDFFlags.DeltaReflection), mi.UInt32(+mi.BSDFFlags.DeltaTransmission)
        )
        # radiance is scaled by the squared index ratio on refraction (not importance)
        if ctx.mode == mi.TransportMode.Radiance:  # the mode is one value for all lanes
            scale = scale * dr.select(reflect, 1.0, dr.square(eta_ti))
        active = active & (has_r or has_t)
        return bs, dr.select(active, self._lane_weights(scale, lane, mixed), 0.0)

    def split(self, r_i, tir, cos_theta_i, lam):
        """(R, T) of the interface for light meeting it at cos θ = `cos_theta_i` (> 0 from the exterior) at
        wavelength `lam` (nm; None in the mono variants), given Fresnel's unpolarised `r_i` and where it
        totally reflects (`tir`): here the bare interface's R = r_i, T = 1 − R (`coated_dielectric`: the coating's)."""
        return r_i, 1.0 - r_i

    def sampled_transmission(self, r, t):
        """The weight of a refraction chosen with probability 1 − R (`fresnel` "sample"): T/(1 − R), which
        is 1 for the bare interface, whose R + T = 1."""
        return 1.0

    def _lane(self, wavelengths, sample1):
        """(wavelength the interface follows, its lane, sample1 left for the Fresnel choice, whether
        the lanes differ). Equal lanes: lane 0, sample1 unchanged; else a lane chosen by sample1."""
        if not mi.is_spectral:
            return None, 0, sample1, False
        mixed = (
            (wavelengths[1] != wavelengths[0]) | (wavelengths[2] != wavelengths[0]) | (wavelengths[3] != wavelengths[0])
        )
        scaled = sample1 * 4.0
        lane = dr.select(mixed, dr.minimum(mi.UInt32(scaled), 3), 0)
        sample1 = dr.select(mixed, scaled - mi.Float(lane), sample1)
        lam = dr.select(
            lane == 0,
            wavelengths[0],
            dr.select(lane == 1, wavelengths[1], dr.select(lane == 2, wavelengths[2], wavelengths[3])),
        )
        return lam, lane, sample1, mixed

    @staticmethod
    def _lane_weights(scale, lane, mixed) -> mi.Spectrum:
        """`scale` in every lane, or, where the lanes carry different wavelengths, 4·scale in the
        followed lane and 0 in the others."""
        if not mi.is_spectral:
            return mi.Spectrum(scale)
        weight = mi.Spectrum(scale)
        for i in range(4):
            weight[i] = dr.select(mixed, dr.select(lane == i, 4.0 * scale, 0.0), scale)
        return weight

    def eval(self, ctx, si, wo, active=True):
        return mi.Spectrum(0.0)

    def pdf(self, ctx, si, wo, active=True):
        return mi.Float(0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return mi.Spectrum(0.0), mi.Float(0.0)

    def traverse(self, callback) -> None:
        pass

    def to_string(self) -> str:
        return f"SellmeierDielectric[int={self.int_glass.name}, ext={self.ext_glass.name}, fresnel={self.fresnel}" + (
            "]" if mi.is_spectral else f", {self.wavelength:g} nm]"
        )


def register() -> None:
    mi.register_bsdf("sellmeier_dielectric", SellmeierDielectric)  # this variant's class, bound now
