"""The CODE V sequence-file language (`codev`): how a .seq text splits into commands, which command a word
names, and which commands are read, read past (IGNORED) or refused (REFUSED, with what they describe)."""

from __future__ import annotations

import re

ASPHERIC = "ABCDEFGHJ"  # the coefficients of r⁴, r⁶, … r²⁰
FIELDS = {"YAN": "angle", "YOB": "object height", "YIM": "paraxial image height", "YRI": "real image height"}
APERTURES = {"EPD": "epd", "FNO": "fnum", "NAO": "na"}
# optimisation codes: CCY/CCX (curvature), THC (thickness), GLC (glass), KC (conic), AC … JC (the aspheric
# coefficients A … J); each says whether its value varies, not what it is. UID: a surface's identifier
# (CODE V 2026 writes one per surface); CMP, DSX, DSY, BTX, BTY: compensators and tolerances
IGNORED = frozenset(
    [
        "LEN",
        "GO",
        "END",
        "INI",
        "WTW",
        "WTF",
        "DOR",
        "CCY",
        "CCX",
        "THC",
        "GLC",
        "DER",
        "KC",
        "UID",
        "CMP",
        "DSX",
        "DSY",
        "BTX",
        "BTY",
    ]
    + [k + "C" for k in ASPHERIC]
)
VIGNETTING = ("VUX", "VLX", "VUY", "VLY")  # the pupil's fraction cut off per field: +x, −x, +y, −y
SYSTEM = ("TIT", "TITLE", "DIM", "WL", "REF", "XAN", "XOB", "XIM", "XRI", *FIELDS, *APERTURES, *VIGNETTING)
ZERO_IS_NOTHING = ("CUF",)
REFUSED = {
    "RET": "coordinate returns to a named surface",
    "REFL": "mirrors",
    "DOE": "diffractive surfaces",
    "DIF": "diffractive surfaces",
    "HOE": "holographic surfaces",
    "HCO": "holographic surfaces",
    "SPS": "special surface shapes",
    "YTO": "toric surfaces",
    "XTO": "toric surfaces",
    "RDX": "anamorphic surfaces (an x radius)",
    "CUX": "anamorphic surfaces (an x curvature)",
    "REX": "rectangular apertures",
    "REY": "rectangular apertures",
    "ELX": "elliptical apertures",
    "ELY": "elliptical apertures",
    "OBS": "obscurations",
    "ZOO": "zoom positions",
    "NA": "image-space NA apertures (use EPD, FNO or NAO)",
    "TEL": "telecentric object spaces",
    "CUF": "fringe curvatures",
}
SURFACE_COMMANDS = (
    "SO",
    "S",
    "STO",
    "SI",
    "RDY",
    "CUY",
    "THI",
    "GLA",
    "CIR",
    "K",
    *ASPHERIC,
    "SLB",
    "PIM",
    "SPH",
    "ASP",
    "CON",
)
KNOWN = frozenset((*SURFACE_COMMANDS, *SYSTEM, *IGNORED, *REFUSED, "RDM", "CUM", "TEM", "PRE", "PRV"))


def command(word: str) -> str:
    """The command a word names: CODE V knows its commands by their first three letters (STOP is STO), so a
    longer word that is no command of its own is read as those; one beginning with a refused command
    (REFLECT) stays refused."""
    if word in KNOWN:
        return word
    refused = [k for k in REFUSED if len(k) > 2 and word.startswith(k)]
    return refused[0] if refused else word[:3] if word[:3] in KNOWN else word


def commands(text: str):
    """(line number, [tokens]) of each command: `;` separates, `!` comments, quotes group, a line ending
    in `&` goes on on the next."""
    token = re.compile(r"'[^']*'|\"[^\"]*\"|;|!|&|[^\s;!&'\"]+")
    tokens: list[str] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        found = token.findall(raw)
        found = found[: found.index("!")] if "!" in found else found
        going_on = found[-1:] == ["&"]
        for t in found[:-1] if going_on else found:
            if t == ";":
                if tokens:
                    yield number, tokens
                tokens = []
            elif t != "&":
                tokens.append(t)
        if tokens and not going_on:
            yield number, tokens
            tokens = []
    if tokens:
        yield number, tokens
