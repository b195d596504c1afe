"""What the commands share: parsing of command-line values, the option groups several commands take,
and the one shape of an option spec (`OptionSpec`, its fields declared by `option`)."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import Field, dataclass, field, fields, replace
from typing import Any

from .errors import SolasError
from .userfiles import read_toml

_WXH = re.compile(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*")


def parse_wxh(text: str | tuple[int, int], what: str, minimum: int = 1) -> tuple[int, int]:
    """ "WxH" (columns × rows, e.g. "32x24") or a (rows, columns) tuple → (rows, columns), each ≥ `minimum`."""
    if isinstance(text, tuple):
        rows, cols = text
        ok = all(isinstance(v, int) and not isinstance(v, bool) for v in text)
    else:
        m = _WXH.fullmatch(str(text))
        ok = m is not None
        rows, cols = (int(m.group(2)), int(m.group(1))) if m else (0, 0)
    if not ok or rows < minimum or cols < minimum:
        raise SolasError(f"{what} {text!r} must look like 32x24 (columns x rows), each >= {minimum}")
    return rows, cols


def wxh_text(value: tuple[int, int]) -> str:
    """A (rows, columns) pair as `parse_wxh` reads it: "COLSxROWS"."""
    return f"{value[1]}x{value[0]}"


def parse_size_mm(text: str, what: str) -> tuple[float, float]:
    """ "WxH" in mm (e.g. "23.6x15.8") → (width, height): a physical size, unlike `parse_wxh`'s pixel
    counts (which it returns as rows, columns)."""
    parts = str(text).lower().replace("×", "x").split("x")
    try:
        if len(parts) != 2:
            raise ValueError
        return float(parts[0]), float(parts[1])
    except ValueError:
        raise SolasError(f"{what} {text!r} must look like 23.6x15.8 (width x height in mm)") from None


def floats(text: str, what: str) -> list[float]:
    """Comma-separated numbers, at least one."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        values = []
    if not values:
        raise SolasError(f"{what} {text!r} must be one or more comma-separated numbers")
    return values


def positive_ints(text: str, what: str) -> tuple[int, ...]:
    """Comma-separated positive integers, at least one."""
    try:
        values = tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        values = ()
    if not values or min(values) < 1:
        raise SolasError(f"{what} {text!r} must be comma-separated positive integers")
    return values


def add_image_input_options(p, boundaries, variants) -> None:
    """The options of a command that degrades one input image both ways (PSF-grid convolution and
    direct render) and compares them, after its LENS (`optics.commands.add_lens_argument`): IMAGE, -o DIR, --sensor | --scale, --seeds of the
    reference render, --fov-deg, --boundary, --linear, --variant. `boundaries` and `variants` are the
    choices (`optics.camera.BOUNDARIES`, `render.mitsuba.VARIANTS`), given by the caller so that this
    module imports no stage."""
    p.add_argument("image", help="input image, the ideal image spanning ±fov (PNG/JPEG sRGB, EXR linear)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--sensor", help="resample the image to COLSxROWS first (area average); it is the sensor")
    size.add_argument("--scale", type=float, help="resample the image by this factor in (0, 1] first")
    p.add_argument("--seeds", type=int, default=2, help="renders the reference is averaged from (>= 2)")
    p.add_argument("--fov-deg", type=float, help="half the horizontal field the image spans (default: the lens's)")
    p.add_argument("--boundary", choices=boundaries, default="edge", help="padding / object outside the image")
    p.add_argument("--linear", action="store_true", help="PNG/JPEG values are already linear")
    p.add_argument("--variant", choices=variants, help="Mitsuba variant of the render")


def toml_table(path, table: str, what: str) -> dict:
    """The one `[table]` of the TOML file `path` (and nothing else in it), read by `userfiles.read_toml`;
    `what` is its kind there (e.g. "sensor model"), which names the file in the one-line errors."""
    data = read_toml(path, what)
    if not isinstance(data.get(table), dict) or set(data) != {table}:
        raise SolasError(
            f"{what} {str(path)!r} must hold one [{table}] table (and nothing else); "
            f"found {', '.join(sorted(data)) or 'nothing'}"
        )
    return data[table]


@dataclass(frozen=True)
class Flag:
    """How a field of an option spec is given on the command line (declared with the field by `option`)."""

    help: str | Callable[[], str]  # argparse's help (% written %%); a callable is read when the parser is built
    name: str | None = None  # the flag, e.g. "--psf-method"; None: the field's name, "--" and dashes for "_"
    parse: Callable[[str], Any] | None = None  # the flag's text → the field's value (None: the text)
    choices: tuple | Callable[[], tuple] | None = None  # a callable: those of a registry when the parser is built
    metavar: str | None = None
    shown: Callable[[Any], str] = str  # the default as the help writes it

    @property
    def dest(self) -> str:
        """The argparse attribute of the flag: its name without dashes (--psf-method: psf_method)."""
        return self.name.lstrip("-").replace("-", "_")

    def read(self, text):
        """The value of the flag's `text`: `parse`'s, its SolasError as it is, its ValueError (int's,
        float's) a SolasError naming the flag."""
        if self.parse is None or not isinstance(text, str):
            return text
        try:
            return self.parse(text)
        except SolasError:  # a parser's own message (a sensor's WxH) names the value and what is allowed
            raise
        except ValueError:
            kind = "an integer" if self.parse is int else "a number"
            raise SolasError(f"{self.name} {text!r} must be {kind}") from None


def option(
    help: str | Callable[[], str],
    default=None,
    *,
    flag: str | None = None,
    parse=None,
    choices=None,
    metavar: str | None = None,
    shown: Callable[[Any], str] = str,
) -> Any:
    """A field of an `OptionSpec` declared with its command-line flag (`Flag`: its help, the flag when it
    is not the field's name, how its text is read, its choices): adding an option to a spec adds it to
    every command that takes the spec's flags. A bool field is a flag without a value (store_true)."""
    return field(default=default, metadata={"flag": Flag(help, flag, parse, choices, metavar, shown)})


class OptionSpec:
    """The base of the option specs (`psf.spec.GridSpec`, `render.spec.RenderSpec`,
    `convolution.spec.DegradeSpec`): frozen dataclasses whose fields are declared by `option`, so that
    a command adds their flags (`add_flags`) and builds the spec from its arguments (`from_args`) in one
    way. Fields without a flag (objects a command builds from several flags) are plain fields, given to
    `from_args` by the command. The flags have no argparse default: a flag not given leaves the spec's
    default (or the command's, `defaults`), which the help states."""

    @classmethod
    def fields_by_name(cls) -> dict[str, Field]:
        """The spec's dataclass fields by name, in order."""
        return {f.name: f for f in fields(cls)}

    @classmethod
    def flags(cls, names=None) -> dict[str, Flag]:
        """Field name → its Flag (its flag's name filled in) for the fields `names` (None: every field
        with a flag), in that order."""
        by_name = cls.fields_by_name()
        names = [n for n in by_name if "flag" in by_name[n].metadata] if names is None else names
        out = {}
        for name in names:
            flag = by_name[name].metadata["flag"]
            out[name] = replace(flag, name=flag.name or "--" + name.replace("_", "-"))
        return out

    @classmethod
    def add_flags(cls, parser, names=None, *, defaults: dict | None = None, sweep: tuple[str, ...] = ()) -> None:
        """Add the flags of the fields `names` (None: all) to `parser` (or an argument group), each help
        stating the default (`defaults`: field name → a default the command applies itself); a field of
        `sweep` takes a comma-separated list (`given` returns its values)."""
        by_name = cls.fields_by_name()
        for name, flag in cls.flags(names).items():
            text = flag.help() if callable(flag.help) else flag.help
            default = by_name[name].default
            if isinstance(default, bool):
                parser.add_argument(flag.name, dest=flag.dest, action="store_true", default=None, help=text)
                continue
            value = (defaults or {}).get(name, default)
            if value is not None and "default" not in text:
                text += f" (default: {flag.shown(value).replace('%', '%%')})"
            choices = flag.choices() if callable(flag.choices) else flag.choices
            metavar = flag.metavar
            if name in sweep:
                one = metavar or name.upper()
                metavar, choices, text = f"{one}[,{one}…]", None, text + "; a comma-separated list sweeps over it"
            parser.add_argument(flag.name, dest=flag.dest, metavar=metavar, choices=choices, help=text)

    @classmethod
    def given(cls, args, names=None, *, sweep: tuple[str, ...] = ()) -> dict[str, Any]:
        """Field name → value of each flag of `names` (None: all) given in `args` (`add_flags`), read by
        its Flag; a field of `sweep` → its list of values."""
        out: dict[str, Any] = {}
        for name, flag in cls.flags(names).items():
            text = getattr(args, flag.dest, None)
            if text is None:
                continue
            if name in sweep:
                out[name] = [flag.read(v.strip()) for v in str(text).split(",") if v.strip()]
                if not out[name]:
                    raise SolasError(f"{flag.name} {text!r} needs at least one value")
            else:
                out[name] = flag.read(text)
        return out

    @classmethod
    def from_args(cls, args, names=None, *, defaults: dict | None = None, **built):
        """The spec of the flags `names` (None: all) given in `args`, the others at `defaults` (field name
        → value: the command's own) or the spec's; `built`: the fields the command built itself (from
        flags of their own)."""
        return cls(**{**(defaults or {}), **cls.given(args, names), **built})
