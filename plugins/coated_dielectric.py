"""`coated_dielectric` (BSDF): `sellmeier_dielectric` with a thin-film coating on the interface, the
lens as real coated glass in the mesh scene (`solas_mi.render.scene`: every coated surface's cap).
Mitsuba 3 has no thin-film dielectric.

| parameter   | type   | unit | default | meaning                                                          |
|-------------|--------|------|---------|------------------------------------------------------------------|
| `coating`   | string | —    | "none"  | the coating as a lens file states it: a kind's name, or its table as JSON |

and every parameter of `sellmeier_dielectric` (`int_glass`, `ext_glass`, `fresnel`, `wavelength`,
`temperature_c`, `pressure_kpa`). The coating table is a lens file's ``[surface.coating]`` (`kind` and the
kind's options, `solas_mi.optics.coating.KINDS`), e.g. ``{"kind": "quarter_wave", "material": "MgF2",
"design_nm": 550}``; its layers are listed from the exterior (the normal's side, air in a lens) inward, and
met in reverse from the interior, as `optics.coating` applies them. "none" is the bare interface,
`sellmeier_dielectric` itself.

The reflectance R and transmittance T are the coating's unpolarised ones, (s + p)/2, by the transfer-matrix
method at the path's wavelength and angle of incidence (`optics.coating`), bilinear in the table the
tracer uses (1 nm × 1/512 in cos θ, within 2e-5 of the matrix; `optics.coated`; the matrix itself in the
scalar variants). An absorbing stack has R + T < 1. With `fresnel`:
- "transmit": refract with weight T;
- "sample": reflect with probability R, else refract with weight T/(1 − R) (1 for a lossless coating);
- "off": refract with weight one, the coating ignored (the sequential tracer's radiometry).
Total internal reflection (the bare interface's, which no film changes) reflects all in every mode.
Components and lanes as in `sellmeier_dielectric`: the interface follows one wavelength, and the coating
is taken there.
"""

from __future__ import annotations

import json

import drjit as dr
import mitsuba as mi
from solas_mi.plugins.sellmeier_dielectric import SellmeierDielectric

from solas_mi.errors import SolasError
from solas_mi.optics.coated import coating_power
from solas_mi.optics.coating import coating_from_table


def parse_coating(text: str):
    """The `Coating` of the `coating` parameter (None for "none"): a kind's name or a JSON table."""
    where = "coated_dielectric"
    if text.lstrip().startswith("{"):
        try:
            table = json.loads(text)
        except json.JSONDecodeError as exc:
            raise SolasError(f"{where}: coating {text!r} is not a JSON table ({exc.msg})") from None
        return coating_from_table(table, where)
    return coating_from_table(text, where)


class CoatedDielectric(SellmeierDielectric):
    """The `coated_dielectric` BSDF (parameters: the module docstring)."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        self.coating = parse_coating(str(props.get("coating", "none")))
        if self.coating is not None:
            ftype = mi.Float if dr.is_jit_v(mi.Float) else float
            media = {"front": (self.ext_glass, self.int_glass), "back": (self.int_glass, self.ext_glass)}
            self.power = {
                (side, reflect): coating_power(self.coating, *pair, ftype, reflect)
                for side, pair in media.items()
                for reflect in (True, False)
            }

    def split(self, r_i, tir, cos_theta_i, lam):
        if self.coating is None:
            return super().split(r_i, tir, cos_theta_i, lam)
        um = mi.Float(lam if mi.is_spectral else self.wavelength) * 1e-3
        front = cos_theta_i > 0.0
        r, t = (
            dr.select(front, self.power["front", q](um, cos_theta_i), self.power["back", q](um, cos_theta_i))
            for q in (True, False)
        )
        return dr.select(tir, 1.0, r), dr.select(tir, 0.0, t)

    def sampled_transmission(self, r, t):
        return t / dr.maximum(1.0 - r, 1e-12)  # R = 1 (total reflection, an ideal mirror): never refracted

    def to_string(self) -> str:
        coating = "none" if self.coating is None else json.dumps(self.coating.table())
        return super().to_string()[:-1].replace("SellmeierDielectric", "CoatedDielectric") + f", coating={coating}]"


def register() -> None:
    mi.register_bsdf("coated_dielectric", CoatedDielectric)  # this variant's class, bound now
