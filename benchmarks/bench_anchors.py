"""The SOLAS doublet's anchors (first-order data, spot radii, chief ray) against the values that
the design notes (DESIGN.md) record from the SOLAS paper and Zemax (the last column, fixed references).

Run: .venv/bin/python benchmarks/bench_anchors.py
Prints the Markdown table of the validation page "Anchors and KrakenOS" (a few seconds).
"""

from __future__ import annotations

from solas_mi import Lens, paraxial, spot

WAVELENGTHS = (486.0, 531.0, 656.0)
# the published anchors (DESIGN.md, "measured physics facts"), per row: the text of the last column
PUBLISHED = {
    "EFL (mm)": "99.9395 / 99.9468 / 100.0882",
    "f/# (EFL/EPD)": "7.991 / 7.991 / 8.016",
    "RMS spot 0° (µm), 20 hexapolar rings": "20.60 / 19.83 / 24.39",
    "RMS spot ±2° (µm), centroid reference": "8.58 / 8.06 / 10.37",
    "RMS spot 0° (µm), converged area-uniform": "—",
    "real chief ray at +2° (mm)": "3.4745 at 531 nm",
}


def rows(lens: Lens) -> dict[str, list[str]]:
    """Each quantity's value per wavelength, printed to the digits the page quotes."""
    out: dict[str, list[str]] = {name: [] for name in PUBLISHED}
    for w in WAVELENGTHS:
        p = paraxial(lens, w)
        at_two = spot(lens, (0.0, 2.0), w)
        out["EFL (mm)"].append(f"{p.efl_mm:.5f}")
        out["f/# (EFL/EPD)"].append(f"{p.f_number:.4f}")
        out["RMS spot 0° (µm), 20 hexapolar rings"].append(f"{spot(lens, (0.0, 0.0), w).rms_radius_um():.3f}")
        out["RMS spot ±2° (µm), centroid reference"].append(f"{at_two.rms_radius_um():.3f}")
        out["RMS spot 0° (µm), converged area-uniform"].append(
            f"{spot(lens, (0.0, 0.0), w, 'grid', 400).rms_radius_um():.2f}"
        )
        out["real chief ray at +2° (mm)"].append(f"{at_two.chief_ray_mm[1]:.5f}")
    return out


def main() -> None:
    lens = Lens.load("solas-doublet")
    print("| quantity | " + " | ".join(f"{w:g} nm" for w in WAVELENGTHS) + " | DESIGN.md |")
    print("|---|---|---|---|---|")
    for name, values in rows(lens).items():
        print(f"| {name} | {' | '.join(values)} | {PUBLISHED[name]} |")


if __name__ == "__main__":
    main()
