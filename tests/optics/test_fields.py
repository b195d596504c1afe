"""Field types as one strategy (`optics.fields`), chosen once per lens."""

import ast
from pathlib import Path

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.errors import SolasError
from solas_mi.optics.fields import ANGLE, POLAR, POLAR_FIELD_DEG, field_type_for

ROOT = Path(__file__).resolve().parents[2]
FIELDS = ROOT / "solas_mi" / "optics" / "fields.py"


def _sources():
    for base in (ROOT / "solas_mi", ROOT / "plugins"):
        for path in sorted(base.rglob("*.py")):
            yield path, ast.parse(path.read_text())


def test_no_module_tests_the_kind_of_field_itself():
    """The kind is chosen in fields.py alone: no other module reads a `polar_field` flag, compares a field
    with POLAR_FIELD_DEG or asks for a field type other than through `Lens.field_type`."""
    bad = []
    for path, tree in _sources():
        if path == FIELDS:
            continue
        for node in ast.walk(tree):
            name = (
                node.attr
                if isinstance(node, ast.Attribute)
                else node.id
                if isinstance(node, ast.Name)
                else node.name
                if isinstance(node, ast.alias)
                else None
            )
            if name in ("polar_field", "POLAR_FIELD_DEG", "PolarField", "AngleField", "POLAR") or (
                name == "field_type_for" and path.name != "lens.py"
            ):
                bad.append(f"{path.relative_to(ROOT)}:{node.lineno}: {name}")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize(
    "name, kind", [("nikkor-fisheye", POLAR), ("solas-doublet", ANGLE), ("wide-angle-22mm", ANGLE)]
)
def test_each_lens_has_one_field_type(name, kind):
    assert Lens.load(name).field_type is kind


def test_the_choice_is_made_at_the_threshold():
    assert field_type_for(POLAR_FIELD_DEG) is POLAR
    assert field_type_for(np.nextafter(POLAR_FIELD_DEG, 0.0)) is ANGLE
    assert POLAR_FIELD_DEG == 89.0


def test_both_kinds_name_the_same_direction_on_the_axes():
    fields = np.array([[0.0, 0.0], [0.0, 30.0], [-45.0, 0.0], [0.0, -80.0]])
    tangents = ANGLE.incoming(fields)
    d = np.concatenate([tangents, np.ones((len(fields), 1))], axis=1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    assert np.allclose(POLAR.incoming(fields), d, rtol=0, atol=1e-15)


@pytest.mark.parametrize("kind", [ANGLE, POLAR])
def test_the_field_of_a_direction_names_that_direction(kind):
    """field_of(θ, φ) and incoming are inverses: the field of a direction points along it."""
    theta = np.radians(np.array([0.0, 10.0, 40.0, 70.0]))
    phi = np.radians(np.array([0.0, 30.0, 135.0, 250.0]))
    fx, fy = kind.field_of(theta, np.cos(phi), np.sin(phi))
    incoming = kind.incoming(np.stack([fx, fy], axis=-1))
    d = incoming if incoming.shape[1] == 3 else np.concatenate([incoming, np.ones((len(theta), 1))], axis=1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    expected = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    assert np.allclose(d, expected, rtol=0, atol=1e-12)


def test_each_kind_checks_its_own_limits():
    assert POLAR.check((0.0, 120.0)) == (0.0, 120.0)
    for kind, field in (
        (ANGLE, (0.0, 89.0)),
        (POLAR, (0.0, 180.0)),
        (ANGLE, "ab"),
        (POLAR, (float("nan"), 0.0)),
        (ANGLE, None),
    ):
        with pytest.raises(SolasError, match="field"):
            kind.check(field)


def test_lens_info_names_the_field_type(capsys):
    from strict_json import strict_loads

    from solas_mi.cli import main

    assert main(["lens", "info", "nikkor-fisheye", "--json", "--fields", "0,30"]) == 0
    assert strict_loads(capsys.readouterr().out)["field_type"] == "polar"
