"""One shape for every list of methods, formats and layers: a `Registry` maps a name to an `Entry` (its
callable, its own typed `Option`s, a one-line summary and a reference), and everything that lists the
names — the messages that say what is allowed, the command line's choices and help, the documentation's
tables (`describe`, generated at each docs build), the tests — reads them from it. Adding a method is
one `register` call.

Modelled on colour-science's method mappings with one dispatcher (`colour.temperature.CCT_to_xy`:
``CCT_TO_XY_METHODS[method]`` called with ``filter_kwargs(function, **kwargs)``): here each method
declares its own options, and `Registry.options` routes to it only those, checked.

This module imports nothing but the standard library and `errors`, so the command line can build its
choices from a registry without loading NumPy or Dr.Jit; a registry's entries load their own modules
when called.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from numbers import Integral, Real
from typing import Any

from .errors import SolasError


def _number(value) -> str:
    return str(value) if isinstance(value, Integral) else f"{value:g}"


@dataclass(frozen=True)
class Option:
    """A method's own option: its keyword, type (bool, int, float or str), default, allowed values and
    meaning. `label` is how a message names it (its keyword when empty); `minimum` and `maximum` bound
    numbers (inclusive; `above`: the minimum itself is excluded); `choices` lists a string's values."""

    name: str
    kind: type
    default: Any
    meaning: str
    minimum: float | None = None
    maximum: float | None = None
    above: bool = False
    choices: tuple = ()
    label: str = ""

    def allowed(self) -> str:
        """What the option takes, in words ("an integer from 8 to 4096", "true or false", ...)."""
        if self.kind is bool:
            return "true or false"
        if self.choices:
            return "one of " + ", ".join(map(str, self.choices))
        noun = {int: "an integer", float: "a finite number"}.get(self.kind, "a string")
        low, high = self.minimum, self.maximum
        if low is not None and high is not None and not self.above:
            return f"{noun} from {_number(low)} to {_number(high)}"
        bounds = ([f"{'>' if self.above else '>='} {_number(low)}"] if low is not None else []) + (
            [f"<= {_number(high)}"] if high is not None else []
        )
        return " ".join([noun, " and ".join(bounds)]) if bounds else noun

    def fits(self, value) -> bool:
        """Whether `value` is one this option takes."""
        if self.kind is bool or isinstance(value, bool):
            return self.kind is bool and isinstance(value, bool)
        if self.kind is str:
            return isinstance(value, str) and (not self.choices or value in self.choices)
        if not isinstance(value, Integral if self.kind is int else Real) or not math.isfinite(value):
            return False
        low_ok = self.minimum is None or (value > self.minimum if self.above else value >= self.minimum)
        return low_ok and (self.maximum is None or value <= self.maximum)

    def check(self, value):
        """`value` as the option's type; a SolasError naming the option, the value and what is allowed."""
        if not self.fits(value):
            raise SolasError(f"{self.label or self.name} {value!r} must be {self.allowed()} ({self.meaning})")
        return value if self.kind in (bool, str) else self.kind(value)

    def describe(self) -> str:
        """One line for the docs: keyword, what it takes, default, meaning."""
        default = str(self.default).lower() if self.kind is bool else self.default
        return f"`{self.name}` ({self.allowed()}; default {default}): {self.meaning}"


@dataclass(frozen=True)
class Entry:
    """A registered name: its callable, its own options, one summary line, a reference (a citation or
    a link), and what else its registry keeps per name (`extra`: a convolution method's `describe`, a
    label's layer names)."""

    name: str
    function: Callable
    options: tuple[Option, ...] = ()
    summary: str = ""
    reference: str = ""
    extra: dict = field(default_factory=dict)


class Registry:
    """Name → `Entry`, in the order registered (the order every message and list shows). `kind` names
    one entry in messages ("demosaicing method"); `default` is the name taken when none is given;
    `shown`: the keys of `Entry.extra` the docs' table shows (a label's layers). Iterating gives the
    names; `registry[name]` and `get(name)` the entry."""

    def __init__(self, kind: str, default: str | None = None, shown: tuple[str, ...] = ()):
        self.kind, self.default, self.shown = kind, default, shown
        self._entries: dict[str, Entry] = {}

    def register(
        self, name: str, function: Callable | None = None, *, summary: str, options=(), reference: str = "", **extra
    ):
        """Add `name` (a name is registered once; registering the same entry again does nothing). Without
        `function`, a decorator that registers the function it decorates and returns it."""
        if function is None:

            def decorate(f: Callable) -> Callable:
                self.register(name, f, summary=summary, options=options, reference=reference, **extra)
                return f

            return decorate
        entry = Entry(name, function, tuple(options), summary, reference, extra)
        if not isinstance(name, str) or not name.strip() or "\n" in summary or not summary.strip():
            raise SolasError(f"{self.kind} {name!r}: a name and a one-line summary are needed")
        if self._entries.get(name, entry) != entry:
            raise SolasError(f"{self.kind} {name!r} is registered already")
        self._entries[name] = entry
        return entry

    def get(self, name) -> Entry:
        """The entry of `name`; a SolasError listing the names."""
        if not isinstance(name, str) or name not in self._entries:
            raise SolasError(f"{self.kind} {name!r} must be one of {', '.join(self._entries)}")
        return self._entries[name]

    __getitem__ = get

    def names(self) -> tuple[str, ...]:
        """The names, in the order registered."""
        return tuple(self._entries)

    def items(self):
        """(name, entry) pairs, in the order registered."""
        return self._entries.items()

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __contains__(self, name) -> bool:
        return isinstance(name, str) and name in self._entries

    def option_names(self) -> list[str]:
        """Every option any entry takes, sorted."""
        return sorted({o.name for e in self._entries.values() for o in e.options})

    def options(self, name: str, given=None, strict: bool = False) -> dict[str, Any]:
        """The options of `name` among `given` (keyword → value; None or absent: the default), checked.
        The options of the other entries are left out (one set of options serves every method), unless
        `strict`, where they are an error; a keyword no entry takes is always one."""
        given = dict(given or {})
        entry = self.get(name)
        own = [o.name for o in entry.options]
        stray = sorted(set(given) - set(own if strict else self.option_names()))
        if stray and strict:
            raise SolasError(
                f"{self.kind} {name!r} takes no option {', '.join(stray)} (its options: {', '.join(own) or 'none'})"
            )
        if stray:
            noun = self.kind.rpartition(" ")[0] or self.kind
            raise SolasError(
                f"{noun} options {', '.join(stray)} are unknown; allowed: {', '.join(self.option_names())}"
            )
        return {o.name: o.check(o.default if given.get(o.name) is None else given[o.name]) for o in entry.options}

    def help(self) -> str:
        """A help text for a choice among the names: each with its summary, the default marked."""
        return "; ".join(f"{n}{' (default)' if n == self.default else ''}: {e.summary}" for n, e in self.items())

    def option_help(self, option: str) -> str:
        """A help text for `option`: the entries that take it, and its meaning ("geometric, render: rays ×
        rays per PSF")."""
        takers = [(n, o) for n, e in self._entries.items() for o in e.options if o.name == option]
        return f"{', '.join(n for n, _ in takers)}: {takers[0][1].meaning}" if takers else ""

    def describe(self) -> str:
        """A Markdown table of the entries: name (the default marked), the `shown` extras, summary, options,
        reference."""
        head = (self.kind, *self.shown, "what it does", "options", "reference")
        rows = ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
        for name, e in self._entries.items():
            mark = " (default)" if name == self.default else ""
            options = "<br>".join(o.describe() for o in e.options) or "—"
            values = [e.extra.get(key, ()) for key in self.shown]  # a string is one value, a tuple several
            shown = [", ".join(f"`{v}`" for v in ((x,) if isinstance(x, str) else x)) or "—" for x in values]
            cells = (f"`{name}`{mark}", *shown, e.summary, options, e.reference or "—")
            rows.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
        return "\n".join(rows)
