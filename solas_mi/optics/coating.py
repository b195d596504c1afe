"""Thin-film coatings of a lens surface: what a surface's `coating` holds (`Coating`, built by kind
through `KINDS`, a `registry.Registry`), and its reflectance and transmittance per wavelength and angle
of incidence, s and p, by the transfer-matrix (characteristic-matrix) method.

Kinds: `none` (the bare interface: Fresnel's equations), `quarter_wave` (one layer of `material`, a
quarter wave thick at `design_nm`, e.g. MgF₂ at 550 nm), `ideal` (a given reflectance at every
wavelength and angle, the rest transmitted: Zemax's ``I.xx``) and `stack` (layers of materials and
thicknesses in nm, absorbing ones with an extinction coefficient k). A layer's material is a glass name
(`glass.resolve`: catalogues, ``model:n``) or one of `MATERIALS`, coating materials no glass catalogue
holds. Layers are listed from the air side to the glass: where light leaves glass into air the order is
reversed (as Zemax applies a coating), so one coating serves both faces of an element.

Convention (H. A. Macleod, "Thin-Film Optical Filters", 4th ed., CRC Press, 2010, ch. 2): complex index
N = n − ik (k ≥ 0 absorbs), tilted admittances η_s = N cos θ, η_p = N / cos θ, a layer's phase
δ = 2π N d cos θ / λ and matrix [[cos δ, i sin δ / η], [i η sin δ, cos δ]]; with [B, C] the product of
the layers' matrices applied to [1, η_substrate]: r = (η₀B − C)/(η₀B + C), R = |r|²,
T = 4 η₀ Re(η_substrate) / |η₀B + C|², A = 1 − R − T. The incident medium is lossless.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..errors import SolasError
from ..registry import Option, Registry
from . import glass as glass_mod

# Coating materials no glass catalogue holds: Sellmeier (B, C in µm²) of their refractive index.
# MGF2: magnesium fluoride, ordinary ray (the index a thin film's columnar grains give near normal incidence),
# M. J. Dodge, "Refractive properties of magnesium fluoride", Appl. Opt. 23, 1980-1985 (1984), valid
# 0.2-7 µm, as the refractiveindex.info database (CC0 1.0; data/main/MgF2/nk/Dodge-o.yml) gives it.
MATERIALS = {
    "MGF2": glass_mod.Glass(
        "COATING:MGF2",
        "sellmeier",
        ((0.48755108, 0.39875031, 2.3120353), (0.04338408**2, 0.09461442**2, 23.793604**2)),
        (200.0, 7000.0),
    ),
}
MAX_LAYERS = 200  # layers of a stack (a broadband filter holds tens; each costs one matrix product)
MAX_EXTINCTION = 20.0  # k of an absorbing layer (metals: aluminium ~ 7 in the visible)
MAX_DECAY = 600.0  # |Im δ| of one film: its amplitude's decay e^-600 (cos δ stays finite; nothing passes beyond)


class Power(NamedTuple):
    """Reflectance and transmittance (fractions of the incident power) for s and p light."""

    rs: np.ndarray
    rp: np.ndarray
    ts: np.ndarray
    tp: np.ndarray

    @property
    def reflectance(self) -> np.ndarray:
        """Unpolarised reflectance (Rs + Rp)/2."""
        return 0.5 * (self.rs + self.rp)

    @property
    def transmittance(self) -> np.ndarray:
        """Unpolarised transmittance (Ts + Tp)/2."""
        return 0.5 * (self.ts + self.tp)


@dataclass(frozen=True)
class Layer:
    """One film: its material's name and medium, its physical thickness (nm) and extinction coefficient k."""

    material: str
    glass: glass_mod.Glass
    thickness_nm: float
    extinction: float = 0.0

    def index(self, wavelength_nm: np.ndarray) -> np.ndarray:
        """The complex index n − ik at `wavelength_nm`."""
        return np.asarray(self.glass.index(wavelength_nm), dtype=np.complex128) - 1j * self.extinction


@dataclass(frozen=True)
class Coating:
    """A surface's coating: its `kind` (a name of `KINDS`), the values its kind takes (`values`, as the
    lens file gives them) and its films (`layers`, air side first); `reflectance` for `ideal`."""

    kind: str
    values: tuple[tuple[str, object], ...] = ()
    layers: tuple[Layer, ...] = ()
    reflectance: float | None = None

    def table(self) -> dict:
        """The lens file's table of this coating (what `coating_from_table` reads back)."""
        return {"kind": self.kind, **{k: [dict(row) for row in v] if k == "layers" else v for k, v in self.values}}

    def power(self, n_before, n_after, wavelength_nm, cos_before) -> Power:
        """Reflectance and transmittance for light from the medium of index `n_before` (real) into
        `n_after` (real) at `wavelength_nm`, meeting the surface at cos θ = `cos_before` (arrays
        broadcast). Where light leaves glass for a lower index the layers are met in reverse order."""
        shape = np.broadcast(
            np.asarray(n_before), np.asarray(n_after), np.asarray(wavelength_nm), np.asarray(cos_before)
        ).shape
        if self.reflectance is not None:
            r, t = np.full(shape, self.reflectance), np.full(shape, 1.0 - self.reflectance)
            return Power(r, r, t, t)
        layers = self.layers[::-1] if np.all(np.asarray(n_before) > np.asarray(n_after)) else self.layers
        return stack_power(
            n_before,
            [layer.index(wavelength_nm) for layer in layers],
            [layer.thickness_nm for layer in layers],
            n_after,
            wavelength_nm,
            cos_before,
        )


def _forward_root(z: np.ndarray) -> np.ndarray:
    """√z with the branch of a wave that decays forward (Im ≤ 0 in the n − ik convention)."""
    root = np.sqrt(z.astype(np.complex128))
    return np.where(root.imag > 0, -root, root)


def stack_power(n0, indices: list, thicknesses_nm: list, n_sub, wavelength_nm, cos0) -> Power:
    """Rs, Rp, Ts, Tp of films (complex `indices` n − ik, `thicknesses_nm`, incident side first) between a
    lossless incident medium `n0` and a substrate `n_sub`, at cos θ₀ = `cos0` (arrays broadcast); no films:
    Fresnel's equations. The characteristic-matrix method (module docstring)."""
    n0 = np.asarray(n0, dtype=np.float64)
    cos0 = np.clip(np.asarray(cos0, dtype=np.float64), 1e-12, 1.0)  # grazing: T → 0 without 0/0
    if not indices and np.isrealobj(n_sub):
        return fresnel(n0, np.asarray(n_sub, dtype=np.float64), cos0)
    lam = np.asarray(wavelength_nm, dtype=np.float64)
    kx2 = (n0 * n0) * (1.0 - cos0 * cos0)  # (n₀ sin θ₀)², conserved across the films
    out = []
    for tilt in (lambda n, y: y, lambda n, y: n * n / y):  # η_s = N cos θ = y, η_p = N / cos θ = N²/y
        eta0 = tilt(n0, n0 * cos0 + 0j)
        n_s = np.asarray(n_sub, dtype=np.complex128)
        eta_sub = tilt(n_s, _forward_root(n_s * n_s - kx2))
        b, c, log_scale = np.ones_like(eta_sub), eta_sub, 0.0
        for n_j, d in zip(indices[::-1], thicknesses_nm[::-1]):  # the matrices applied from the substrate out
            y = _forward_root(n_j * n_j - kx2)
            eta, delta = tilt(n_j, y), 2.0 * math.pi * y * d / lam
            # an opaque film's e^|Im δ| kept finite (beyond e^-600 nothing passes anyway), and [B, C] rescaled:
            # r takes their ratio only, T the scale, carried as its logarithm
            delta = delta.real + 1j * np.clip(delta.imag, -MAX_DECAY, MAX_DECAY)
            cos_d, sin_d = np.cos(delta), np.sin(delta)
            b, c = cos_d * b + 1j * sin_d / eta * c, 1j * eta * sin_d * b + cos_d * c
            scale = np.maximum(np.abs(b), np.abs(c))
            b, c, log_scale = b / scale, c / scale, log_scale + np.log(scale)
        denominator = eta0 * b + c
        r = np.abs((eta0 * b - c) / denominator) ** 2
        t = 4.0 * eta0.real * eta_sub.real / np.abs(denominator) ** 2 * np.exp(-2.0 * log_scale)
        out += [r, np.maximum(t, 0.0)]
    return Power(out[0], out[2], out[1], out[3])


def fresnel(n0: np.ndarray, n1: np.ndarray, cos0: np.ndarray) -> Power:
    """Fresnel's equations of a bare interface between lossless media, in real arithmetic (the films'
    method without films, faster): beyond the critical angle all is reflected."""
    mu = n0 / n1
    k2 = 1.0 - mu * mu * (1.0 - cos0 * cos0)
    cos1 = np.sqrt(np.maximum(k2, 0.0))
    rs = ((mu * cos0 - cos1) / (mu * cos0 + cos1)) ** 2
    rp = ((cos0 - mu * cos1) / (cos0 + mu * cos1)) ** 2
    rs, rp = np.where(k2 > 0, rs, 1.0), np.where(k2 > 0, rp, 1.0)
    return Power(rs, rp, 1.0 - rs, 1.0 - rp)


KINDS = Registry("coating kind", default="none")
"""The coating kinds by name (a `solas_mi.registry.Registry`): each entry's function makes a `Coating`
from a lens file's [surface.coating] table."""
MATERIAL = Option("material", str, "MGF2", "the layer's material: a coating material (MGF2) or a glass name")
DESIGN_NM = Option(
    "design_nm",
    float,
    550.0,
    "the wavelength (nm) at which the layer is a quarter wave thick",
    minimum=100.0,
    maximum=20000.0,
)
REFLECTANCE = Option(
    "reflectance",
    float,
    0.0,
    "the fraction of the power reflected at every wavelength and angle (the rest is transmitted)",
    minimum=0.0,
    maximum=1.0,
)


def layer_glass(material, where: str) -> glass_mod.Glass:
    """The medium of a layer's `material`: one of `MATERIALS` or a glass name (`glass.resolve`)."""
    if not isinstance(material, str) or not material.strip():
        raise SolasError(
            f"{where}: layer material {material!r} must be a name: one of {', '.join(MATERIALS)}, "
            "or a glass name (catalogue or model:n)"
        )
    if material.upper() in MATERIALS:
        return MATERIALS[material.upper()]
    try:
        return glass_mod.resolve(material)
    except SolasError as exc:
        raise SolasError(
            f"{where}: layer material: {exc} (or one of the coating materials {', '.join(MATERIALS)})"
        ) from None


@KINDS.register("none", summary="the bare interface: Fresnel's equations")
def _none(where: str, **_) -> Coating:
    return Coating("none")


@KINDS.register(
    "quarter_wave",
    options=(MATERIAL, DESIGN_NM),
    summary="one layer of `material`, a quarter wave thick at `design_nm` (nm)",
)
def _quarter_wave(where: str, material: str, design_nm: float) -> Coating:
    g = layer_glass(material, where)
    thickness = design_nm / (4.0 * float(g.index(design_nm)))
    return Coating("quarter_wave", (("material", material), ("design_nm", design_nm)), (Layer(material, g, thickness),))


@KINDS.register(
    "ideal",
    options=(REFLECTANCE,),
    summary="`reflectance` at every wavelength and angle, the rest transmitted (Zemax's I.xx)",
)
def _ideal(where: str, reflectance: float) -> Coating:
    return Coating("ideal", (("reflectance", reflectance),), reflectance=reflectance)


@KINDS.register(
    "stack",
    summary="films air side first: `layers` = [{material, thickness_nm, k}, ...] (k: "
    "extinction coefficient, default 0)",
    layers=True,
)
def _stack(where: str, layers) -> Coating:
    if (
        not isinstance(layers, list)
        or not 1 <= len(layers) <= MAX_LAYERS
        or not all(isinstance(row, dict) for row in layers)
    ):
        raise SolasError(
            f"{where}: layers = {layers!r} must be a list of 1 to {MAX_LAYERS} tables {{material, thickness_nm, k}}"
        )
    films = []
    for i, row in enumerate(layers, start=1):
        ident = f"{where}: layer {i}"
        unknown = sorted(set(row) - {"material", "thickness_nm", "k"})
        if unknown:
            raise SolasError(f"{ident}: unknown keys {', '.join(unknown)}; allowed: material, thickness_nm, k")
        d, k = row.get("thickness_nm"), row.get("k", 0.0)
        if not _number(d) or not 0 <= d <= 1e6:
            raise SolasError(f"{ident}: thickness_nm = {d!r} must be a number from 0 to 1e6 (nm)")
        if not _number(k) or not 0 <= k <= MAX_EXTINCTION:
            raise SolasError(f"{ident}: k = {k!r} must be an extinction coefficient from 0 to {MAX_EXTINCTION:g}")
        films.append(Layer(str(row.get("material")), layer_glass(row.get("material"), ident), float(d), float(k)))
    rows = tuple(
        (("material", f.material), ("thickness_nm", f.thickness_nm), *((("k", f.extinction),) if f.extinction else ()))
        for f in films
    )
    return Coating("stack", (("layers", rows),), tuple(films))  # rows as tuples: a lens is hashable


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def coating_from_table(value, where: str) -> Coating | None:
    """A surface's `coating` in a lens file: a kind's name (its defaults) or a table with `kind` and the
    kind's options; None for "none" (the bare surface, the default)."""
    table = {"kind": value} if isinstance(value, str) else value
    if not isinstance(table, dict) or "kind" not in table:
        raise SolasError(
            f"{where}: coating = {value!r} must be a kind ({', '.join(KINDS)}) or a table with kind and its options"
        )
    given = {k: v for k, v in table.items() if k != "kind"}
    try:
        entry = KINDS.get(table["kind"])
        layers = given.pop("layers", None) if entry.extra.get("layers") else None
        options = KINDS.options(entry.name, given, strict=True)
    except SolasError as exc:
        raise SolasError(f"{where}: coating: {exc}") from None
    coating = entry.function(
        f"{where}: coating", **options, **({"layers": layers} if entry.extra.get("layers") else {})
    )
    return None if coating.kind == "none" else coating


def zemax_coating(name: str, where: str) -> dict:
    """The coating table of a Zemax COAT name: ``I.xx`` an ideal coating of transmittance 0.xx (reflectance
    1 − 0.xx); a named coating of a coating file cannot be read without that file, refused by name."""
    text = name.strip()
    if text.upper().startswith("I.") and text[2:].isdigit():
        return {"kind": "ideal", "reflectance": float(f"{1.0 - float('0' + text[1:]):.12g}")}  # 1 − 0.99: 0.01
    raise SolasError(
        f"{where}: COAT {text!r} names a coating of a Zemax coating file (COATING.DAT, or the one "
        "COFN names), which the lens file does not hold; only the ideal I.xx coatings are read: "
        "state it in a .toml lens file as coating = {kind = ..., ...}, or delete the COAT line "
        "for a bare surface"
    )


def to_zemax(coating: Coating | None, where: str) -> list[str]:
    """The COAT line of `coating` in a .zmx file ([] for none): ``I.xx`` for an ideal coating of transmittance
    0 < T < 1 to 12 digits; SolasError for others, which a .zmx file holds only by a coating file's name."""
    if coating is None:
        return []
    digits = f"{1.0 - (coating.reflectance or 0.0):.12f}".rstrip("0")
    if coating.kind != "ideal" or not digits.startswith("0.") or digits == "0.":
        raise SolasError(
            f"{where}: a {coating.kind} coating has no .zmx form here (only the ideal I.xx, "
            "0 < T < 1); save it as .toml"
        )
    return [f"  COAT I.{digits[2:]}"]


# The tracer's table of a coating's unpolarised transmittance: wavelengths every TABLE_STEP_NM nm over the
# media's common range within TABLE_RANGE_NM, cos θ in TABLE_COS steps; bilinear between nodes (measured: within
# 2e-5 of the transfer matrix for a three-layer absorbing stack, 380-780 nm, every angle; a render's weight).
TABLE_RANGE_NM, TABLE_STEP_NM, TABLE_COS = (300.0, 1100.0), 1.0, 513


def transmittance_table(
    coating: Coating, before: glass_mod.Glass, after: glass_mod.Glass, reflect: bool = False
) -> tuple[float, float, int, np.ndarray]:
    """The unpolarised transmittance (with `reflect`: reflectance) of `coating` from medium `before` into
    `after` on a grid, as the tracer interpolates it: (first wavelength nm, step nm, wavelengths, values
    (wavelengths × TABLE_COS) by cos θ from 0 to 1 in the medium of incidence). T is reciprocal: the same
    either way through; R of an absorbing stack is not."""
    lo = max(TABLE_RANGE_NM[0], before.range_nm[0], after.range_nm[0], *(f.glass.range_nm[0] for f in coating.layers))
    hi = min(TABLE_RANGE_NM[1], before.range_nm[1], after.range_nm[1], *(f.glass.range_nm[1] for f in coating.layers))
    count = int((hi - lo) // TABLE_STEP_NM) + 1
    lam = lo + TABLE_STEP_NM * np.arange(count)
    cos = np.linspace(0.0, 1.0, TABLE_COS)
    power = coating.power(before.index(lam)[:, None], after.index(lam)[:, None], lam[:, None], cos[None, :])
    t = power.reflectance if reflect else power.transmittance
    return lo, TABLE_STEP_NM, count, np.ascontiguousarray(t, dtype=np.float64)


def metadata(lens) -> dict:
    """What `lens info` and PSF metadata say of a lens's coatings and iris ({} for a bare, round one):
    each coated surface, and the on-axis chief ray's transmittance at the primary wavelength with the
    coatings and bare (it meets every surface at normal incidence)."""
    out = {}
    coated = [(k, s) for k, s in enumerate(lens.surfaces, start=1) if s.coating is not None]
    if coated:
        w = lens.primary_wavelength
        media = [lens.object_glass] + [s.glass for s in lens.surfaces]
        crossings = [
            (s, float(media[k].index(w)), float(media[k + 1].index(w)))
            for k, s in enumerate(lens.surfaces)
            if media[k] != media[k + 1]
        ]
        with_ = np.prod(
            [
                (s.coating.power(a, b, w, 1.0) if s.coating else fresnel(a, b, 1.0)).transmittance
                for s, a, b in crossings
            ]
        )
        bare = np.prod([fresnel(a, b, 1.0).transmittance for _, a, b in crossings])
        kinds = "; ".join(f"surface {k}: {s.coating.kind} {dict(s.coating.values)}" for k, s in coated)
        out["coatings"] = (
            f"{kinds}; on-axis transmittance at {w:g} nm {float(with_):.4f} (bare surfaces: {float(bare):.4f})"
        )
    stop = lens.surfaces[lens.stop_index]
    if stop.blades:
        share = stop.iris_area() / (math.pi * stop.semi_diameter**2)
        sides = (
            f"blades curved {stop.blade_curvature:g} (arcs of {1.0 / stop.blade_curvature:g} clear radii)"
            if stop.blade_curvature
            else "straight blades"
        )
        out["iris"] = (
            f"{stop.blades} {sides}, first corner at {stop.blade_rotation:g} deg: a regular "
            f"{stop.blades}-gon inside the stop's circle, {share:.4f} of its area (f/# and pupils: the "
            "circle's)"
        )
    return out
