"""CODE V glass (`codev`): the names a .seq file gives its glass (NAME_VENDOR, bare names, model glass "n_d:V_d"
and the glass codes "nnnnnn.vvvvvv" / "nnn.vvv") as our material names, and its private catalogue (PRV … END):
glasses given as indices at the PWL wavelengths (a table material: the spline through them, `glass.own_material`)
or by the Laurent series (LAU), carried as the lens's own [materials]."""

from __future__ import annotations

import re

from ..errors import SolasError
from . import glass as glass_mod
from .formats import floats as _numbers
from .zemax import GCAT_VENDORS

_MODEL = re.compile(r"^(\d*\.?\d+):(\d*\.?\d+)$")
_CODE = re.compile(r"^(\d{3}|\d{6})\.(\d{2,6})$")
LAURENT_POWERS = [0, 2, -2, -4, -6, -8]  # LAU: n² = A0 + A1 λ² + A2 λ⁻² + A3 λ⁻⁴ + A4 λ⁻⁶ + A5 λ⁻⁸ (λ µm)


def unquote(token: str) -> str:
    return token[1:-1] if token[:1] in "'\"" and token[-1:] == token[:1] and len(token) > 1 else token


def material(token: str, ident: str, own: dict | None = None) -> str:
    """Our material name for a CODE V glass: a private glass of the file (`own`, by name), NAME_VENDOR, a
    bare name, "n_d:V_d" or "nnnnnn.vvvvvv"."""
    name = unquote(token).strip()
    if own and name in own:
        return name
    model, code = _MODEL.match(name), _CODE.match(name)
    if model or code:
        nd, vd = (
            (float(model[1]), float(model[2]))
            if model
            else (1.0 + int(code[1]) / 10 ** len(code[1]), float(code[2][:2] + "." + code[2][2:]))
        )
        try:
            return glass_mod.model_name(nd, vd)
        except SolasError as exc:
            raise SolasError(f"{ident}: {name!r}: {exc} (V_d 0: no dispersion)") from None
    if name.upper() == "REFL":
        raise SolasError(f"{ident}: GLA REFL: mirrors are not supported (refracting surfaces only)")
    bare, _, vendor = name.rpartition("_")
    if not bare or vendor.upper() not in GCAT_VENDORS:
        return name or "AIR"
    ours = GCAT_VENDORS[vendor.upper()]
    key = f"{ours}:{bare.upper()}"
    if glass_mod.candidates(key):
        return key
    squeeze = re.sub(r"[\s\-]", "", bare).upper()
    same = [k for k in glass_mod.candidates(squeeze) if k.split(":", 1)[0] == ours]
    same = same or [
        k
        for k in glass_mod.load_catalog()
        if k.split(":", 1)[0] == ours and re.sub(r"[\s\-]", "", k.split(":", 1)[1]).upper() == squeeze
    ]
    if len(same) == 1:
        return same[0]
    raise SolasError(
        f"{ident}: glass {name!r}: {ours} has no glass {bare!r} in our catalogue"
        + (f" (several match: {', '.join(same)})" if same else "")
    )


class PrivateCatalogue:
    """A PRV … END block being read: PWL (the wavelengths, nm), then per glass 'NAME' n1 n2 … (its indices at
    them) or 'NAME' LAU A0 … A5 (the Laurent series, offered over the model glass's range); `glasses` holds
    them as [materials] tables."""

    def __init__(self):
        self.wavelengths: list[float] = []
        self.glasses: dict[str, dict] = {}

    def read(self, key: str, tokens: list[str], ident: str) -> bool:
        """Take one command of the block; True at its END."""
        if key == "END":
            return True
        if key == "PWL":
            self.wavelengths = _numbers(tokens[1:], f"{ident} PWL")
        elif len(tokens) == 8 and tokens[1].upper() == "LAU":
            self.glasses[unquote(tokens[0])] = {
                "K": _numbers(tokens[2:], f"{ident} {tokens[0]} LAU"),
                "P": LAURENT_POWERS,
                "range_nm": list(glass_mod.MODEL_RANGE_NM),
            }
        else:
            numeric = tokens[0][:1] in "'\"" and not any(t[:1].isalpha() for t in tokens[1:])
            index = _numbers(tokens[1:], f"{ident} {tokens[0]}") if numeric else []
            if not index or len(index) != len(self.wavelengths):
                raise SolasError(
                    f"{ident}: {' '.join(tokens)!r}: a private glass is 'NAME' and one index per PWL "
                    f"wavelength ({len(self.wavelengths)}), or 'NAME' LAU and the six Laurent "
                    "coefficients; other dispersion formulas are not supported"
                )
            order = sorted(range(len(index)), key=lambda i: self.wavelengths[i])
            self.glasses[unquote(tokens[0])] = {
                "wavelengths_nm": [self.wavelengths[i] for i in order],
                "index": [index[i] for i in order],
            }
        return False
