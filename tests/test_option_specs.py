"""The one shape of an option spec (`options.option`, `options.OptionSpec`): a field declared with its
flag gives the command's flag, its help (with the default), how its text is read, and the spec built
from the parsed arguments; GridSpec, RenderSpec and DegradeSpec are made so."""

import argparse
from dataclasses import dataclass, field

import pytest

from solas_mi.cli import Parser
from solas_mi.errors import SolasError
from solas_mi.options import Flag, OptionSpec, option, parse_wxh, wxh_text

KINDS = ["a", "b"]  # a registry's names: the choices are read when the parser is built


@dataclass(frozen=True)
class Demo(OptionSpec):
    size: tuple[int, int] = option("COLSxROWS", (6, 8), parse=lambda t: parse_wxh(t, "--size"), shown=wxh_text)
    count: int = option("how many", 3, parse=int, metavar="N")
    scale: float | None = option("a factor (default: none)", parse=float)
    kind: str = option("which one", "a", flag="--demo-kind", choices=lambda: tuple(KINDS))
    fast: bool = option("go fast", False)
    note: str | None = option("a note")
    extra: object = None  # built by the command from flags of its own


def _parser(**kwargs) -> argparse.ArgumentParser:
    p = Parser(prog="demo")
    Demo.add_flags(p, **kwargs)
    return p


def _help(p) -> str:
    return " ".join(p.format_help().split())


def test_each_field_with_a_flag_is_a_flag_with_its_default_in_the_help():
    KINDS.append("c")
    try:
        p = _parser()
    finally:
        KINDS.pop()
    text = _help(p)
    assert "--size SIZE COLSxROWS (default: 8x6)" in text and "--count N how many (default: 3)" in text
    assert "--scale SCALE a factor (default: none)" in text and "--note NOTE a note" in text
    assert "--demo-kind {a,b,c} which one (default: a)" in text and "--fast go fast" in text
    assert "default: False" not in text and "--extra" not in text
    assert list(Demo.flags()) == ["size", "count", "scale", "kind", "fast", "note"]
    assert (Demo.flags()["kind"].name, Demo.flags()["kind"].dest) == ("--demo-kind", "demo_kind")
    assert (Demo.flags()["scale"].name, Demo.flags()["scale"].dest) == ("--scale", "scale")
    assert "--size SIZE COLSxROWS (default: 32x24)" in _help(_parser(defaults={"size": (24, 32)}))


def test_the_spec_from_the_arguments():
    p = _parser()
    assert Demo.from_args(p.parse_args([])) == Demo()
    args = p.parse_args(["--size", "4x2", "--count", "7", "--scale", "0.5", "--demo-kind", "b", "--fast"])
    assert Demo.from_args(args, extra="x") == Demo((2, 4), 7, 0.5, "b", True, None, "x")
    assert Demo.from_args(args, ["count"]) == Demo(count=7)  # only the flags named
    assert Demo.from_args(p.parse_args([]), defaults={"count": 9}) == Demo(count=9)  # the command's own default
    assert Demo.from_args(p.parse_args(["--count", "1"]), defaults={"count": 9}).count == 1


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--count", "many"], "--count 'many' must be an integer"),
        (["--scale", "x"], "--scale 'x' must be a number"),
        (["--size", "4by2"], "--size '4by2' must look like 32x24"),  # the parser's own message
    ],
)
def test_a_flag_that_does_not_read_is_named(argv, message):
    with pytest.raises(SolasError, match=message):
        Demo.from_args(_parser().parse_args(argv))


def test_a_swept_field_takes_a_list():
    p = _parser(sweep=("count",))
    assert "--count N[,N…] how many (default: 3); a comma-separated list sweeps over it" in _help(p)
    assert Demo.given(p.parse_args(["--count", "1, 2,3"]), sweep=("count",)) == {"count": [1, 2, 3]}
    with pytest.raises(SolasError, match="--count ',' needs at least one value"):
        Demo.given(p.parse_args(["--count", ","]), sweep=("count",))


def test_every_spec_declares_its_flags_with_the_one_helper():
    """Every field of GridSpec and RenderSpec is a flag; DegradeSpec's are, but for the objects its
    commands build from flags of their own (the frame's camera, the camera, the grid's options)."""
    from solas_mi.convolution.spec import DegradeSpec
    from solas_mi.psf.spec import GridSpec
    from solas_mi.render.spec import RenderSpec

    for spec, plain in ((GridSpec, set()), (RenderSpec, set()), (DegradeSpec, {"frame", "camera", "grid_spec"})):
        assert issubclass(spec, OptionSpec)
        fields = spec.fields_by_name()
        assert {n for n, f in fields.items() if not isinstance(f.metadata.get("flag"), Flag)} == plain, spec
        assert set(spec.flags()) == set(fields) - plain


def test_a_plain_field_is_not_a_flag():
    @dataclass(frozen=True)
    class Other(OptionSpec):
        a: int = option("a", 1, parse=int)
        b: list = field(default_factory=list)

    assert list(Other.flags()) == ["a"] and Other.from_args(argparse.Namespace(a="2"), b=[1]) == Other(2, [1])
