"""`sellmeier_dielectric` (BSDF): a smooth dielectric interface between two catalogue (or model)
glasses, the index evaluated per path at its wavelength (`solas_mi.optics.glass`: the catalogue's
Sellmeier formula, or a model glass's two-term fit).

| parameter   | type   | unit | default    | meaning                                              |
|-------------|--------|------|------------|------------------------------------------------------|
| `int_glass` | string | —    | "AIR"      | glass on the side opposite the normal (the interior) |
| `ext_glass` | string | —    | "AIR"      | glass on the normal's side                           |
| `fresnel`   | string | —    | "transmit" | Fresnel losses: "transmit", "sample" or "off"        |

Glass names are those of lens files: "N-BK7", "F2", "model:1.5168/64.17", "AIR".
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
Simulation", PhD thesis, Stanford University, 1997, ch. 5). Paths carry one wavelength (nm) in every
lane (the lens sensor samples it), so lane 0's index serves all four.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from solas_mi.errors import SolasError
from solas_mi.optics.glass import resolve

FRESNEL_MODES = ("transmit", "sample", "off")


class SellmeierDielectric(mi.BSDF):
    """The `sellmeier_dielectric` BSDF (parameters: the module docstring)."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        self.int_glass = resolve(props.get("int_glass", "AIR"))
        self.ext_glass = resolve(props.get("ext_glass", "AIR"))
        self.fresnel = str(props.get("fresnel", "transmit"))
        if self.fresnel not in FRESNEL_MODES:
            raise SolasError(f"sellmeier_dielectric fresnel {self.fresnel!r} must be one of {', '.join(FRESNEL_MODES)}")
        reflection = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        transmission = mi.BSDFFlags.DeltaTransmission | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        self.m_components = [reflection, transmission]
        self.m_flags = reflection | transmission

    def eta(self, wavelengths) -> mi.Float:
        """n_int / n_ext at the path's wavelength (nm)."""
        um = mi.Float(wavelengths[0]) * 1e-3 if mi.is_spectral else mi.Float(0.5876)
        return self.int_glass.index_formula(um, dr.sqrt) / self.ext_glass.index_formula(um, dr.sqrt)

    def sample(self, ctx, si, sample1, sample2, active=True):
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        r_i, cos_theta_t, eta_it, eta_ti = mi.fresnel(cos_theta_i, self.eta(si.wavelengths))
        reflect = (sample1 <= r_i) if self.fresnel == "sample" else (r_i >= 1.0)
        bs = mi.BSDFSample3f()
        bs.wo = dr.select(reflect, mi.reflect(si.wi), mi.refract(si.wi, cos_theta_t, eta_ti))
        bs.pdf = 1.0
        bs.eta = dr.select(reflect, 1.0, eta_it)
        bs.sampled_component = dr.select(reflect, mi.UInt32(0), mi.UInt32(1))
        bs.sampled_type = dr.select(reflect, mi.UInt32(+mi.BSDFFlags.DeltaReflection),
                                    mi.UInt32(+mi.BSDFFlags.DeltaTransmission))
        # radiance is scaled by the squared index ratio on refraction (not importance)
        radiance = ctx.mode == mi.TransportMode.Radiance  # the mode is one value for all lanes
        scale = dr.select(reflect, 1.0, dr.square(eta_ti)) if radiance else mi.Float(1.0)
        if self.fresnel == "transmit":
            scale = dr.select(reflect, scale, scale * (1.0 - r_i))
        return bs, dr.select(active, mi.Spectrum(scale), 0.0)

    def eval(self, ctx, si, wo, active=True):
        return mi.Spectrum(0.0)

    def pdf(self, ctx, si, wo, active=True):
        return mi.Float(0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return mi.Spectrum(0.0), mi.Float(0.0)

    def traverse(self, callback) -> None:
        pass

    def to_string(self) -> str:
        return f"SellmeierDielectric[int={self.int_glass.name}, ext={self.ext_glass.name}, fresnel={self.fresnel}]"


def register() -> None:
    mi.register_bsdf("sellmeier_dielectric", lambda props: SellmeierDielectric(props))
