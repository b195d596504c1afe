"""The generic registry (`solas_mi.registry`): a name registered once, a lookup whose error lists the
names, options typed and checked with one error naming option, value and what is allowed, each entry
given only its own options, and the docs' table."""

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.registry import Option, Registry

SIZE = Option("size", int, 4, "cells per side", minimum=2, maximum=64)
SHARP = Option("sharp", bool, True, "a switch")
GAIN = Option("gain", float, 1.5, "how much", minimum=0, above=True, label="fancy gain")
MODE = Option("mode", str, "fast", "which way", choices=("fast", "exact"))


@pytest.fixture
def things():
    registry = Registry("thing method", default="alpha")
    registry.register(
        "alpha", lambda x, size: x * size, options=(SIZE,), summary="alpha | things", reference="A. Author 2020"
    )

    @registry.register("beta", options=(SHARP, GAIN), summary="beta things", layers=("beta.X", "beta.Y"))
    def beta(x, sharp, gain):
        return x + gain

    assert callable(beta) and registry["beta"].function is beta  # the decorator hands the function back
    return registry


def test_names_keep_their_order_and_a_lookup_lists_them(things):
    assert things.names() == ("alpha", "beta") == tuple(things) and len(things) == 2
    assert "beta" in things and "gamma" not in things and ["alpha"] not in things
    assert things.get("alpha").summary == "alpha | things" and things["alpha"].reference == "A. Author 2020"
    for bad in ("gamma", None, ["alpha"], 3):
        with pytest.raises(
            SolasError,
            match=rf"^thing method {bad!r} must be one of alpha, beta$".replace("[", r"\[").replace("]", r"\]"),
        ):
            things.get(bad)


def test_a_name_is_registered_once(things):
    entry = things["alpha"]
    things.register("alpha", entry.function, options=entry.options, summary=entry.summary, reference=entry.reference)
    with pytest.raises(SolasError, match="thing method 'alpha' is registered already"):
        things.register("alpha", print, summary="another")
    for name, summary in (("", "x"), ("delta", ""), ("delta", "two\nlines")):
        with pytest.raises(SolasError, match="a name and a one-line summary are needed"):
            things.register(name, print, summary=summary)
    assert things.names() == ("alpha", "beta")


def test_each_entry_gets_only_its_own_options_checked(things):
    given = {"size": 8, "sharp": False, "gain": None}
    assert things.options("alpha", given) == {"size": 8}
    assert things.options("beta", given) == {"sharp": False, "gain": 1.5}  # None: the default
    assert things.options("alpha") == {"size": 4}
    with pytest.raises(SolasError, match="^thing options sise are unknown; allowed: gain, sharp, size$"):
        things.options("alpha", {"sise": 3})
    with pytest.raises(SolasError, match=r"^thing method 'alpha' takes no option sharp \(its options: size\)$"):
        things.options("alpha", {"sharp": True}, strict=True)
    with pytest.raises(SolasError, match=r"^size 1 must be an integer from 2 to 64 \(cells per side\)$"):
        things.options("alpha", {"size": 1})


@pytest.mark.parametrize(
    "option, value, message",
    [
        (SIZE, 2.0, "size 2.0 must be an integer from 2 to 64"),
        (SIZE, True, "size True must be an integer from 2 to 64"),
        (SIZE, 65, "size 65 must be an integer from 2 to 64"),
        (SHARP, 1, "sharp 1 must be true or false (a switch)"),
        (SHARP, "false", "sharp 'false' must be true or false"),
        (GAIN, 0, r"fancy gain 0 must be a finite number > 0 \(how much\)"),
        (GAIN, float("nan"), "fancy gain nan must be a finite number > 0"),
        (GAIN, "1", "fancy gain '1' must be a finite number > 0"),
        (MODE, "slow", "mode 'slow' must be one of fast, exact"),
        (Option("n", int, 0, "a count", minimum=0), -1, "n -1 must be an integer >= 0"),
        (Option("x", float, 0.0, "a value", maximum=2.5), 3.0, "x 3.0 must be a finite number <= 2.5"),
    ],
)
def test_a_bad_value_names_option_value_and_what_is_allowed(option, value, message):
    with pytest.raises(SolasError, match=message.replace("(a switch)", r"\(a switch\)")):
        option.check(value)


def test_good_values_come_back_as_the_option_type():
    assert SIZE.check(np.int64(8)) == 8 and type(SIZE.check(np.int64(8))) is int
    assert GAIN.check(2) == 2.0 and type(GAIN.check(2)) is float
    assert SHARP.check(False) is False and MODE.check("exact") == "exact"
    assert Option("big", int, 0, "x", minimum=0, maximum=4294967295).allowed() == "an integer from 0 to 4294967295"


def test_describe_is_a_table_of_every_entry(things):
    shown = Registry("layered thing", shown=("layers",))
    shown.register("beta", print, summary="beta things", layers=("beta.X", "beta.Y"))
    table = things.describe().splitlines()
    assert table[0] == "| thing method | what it does | options | reference |" and len(table) == 2 + len(things)
    assert table[2].startswith("| `alpha` (default) | alpha \\| things | `size` (an integer from 2 to 64; default 4)")
    assert "`sharp` (true or false; default true): a switch<br>`gain` (a finite number > 0; default 1.5)" in table[3]
    assert shown.describe().splitlines()[2] == "| `beta` | `beta.X`, `beta.Y` | beta things | — | — |"
    assert things.help() == "alpha (default): alpha | things; beta: beta things"
    assert things.option_help("gain") == "beta: how much" and things.option_help("nothing") == ""
