from solas_mi import resources


def test_installed_inside_the_package_and_checkout_beside_it(tmp_path, monkeypatch):
    package = tmp_path / "site" / "solas_mi"
    (package / "scenes" / "lenses").mkdir(parents=True)
    monkeypatch.setattr(resources, "_PACKAGE", package)
    assert resources.resource_dir("scenes") == package / "scenes"  # wheel: inside the package
    checkout = tmp_path / "checkout" / "solas_mi"
    checkout.mkdir(parents=True)
    (checkout.parent / "scenes").mkdir()
    (checkout.parent / "pyproject.toml").write_text('[project]\nname = "solas-mi"\n')
    monkeypatch.setattr(resources, "_PACKAGE", checkout)
    assert resources.resource_dir("scenes") == checkout.parent / "scenes"  # checkout: beside it


def test_a_foreign_top_level_scenes_package_is_never_used(tmp_path, monkeypatch):
    """Another distribution that installs site-packages/scenes/ must not hide solas-mi's own lenses."""
    site = tmp_path / "site"
    (site / "solas_mi" / "scenes" / "lenses").mkdir(parents=True)
    (site / "scenes").mkdir()
    (site / "scenes" / "__init__.py").write_text("")
    monkeypatch.setattr(resources, "_PACKAGE", site / "solas_mi")
    assert resources.resource_dir("scenes") == site / "solas_mi" / "scenes"


def test_missing_resources_are_an_error_not_a_guess(tmp_path, monkeypatch):
    (tmp_path / "site" / "solas_mi").mkdir(parents=True)
    (tmp_path / "site" / "scenes").mkdir()  # someone else's, with no solas-mi pyproject beside it
    monkeypatch.setattr(resources, "_PACKAGE", tmp_path / "site" / "solas_mi")
    try:
        resources.resource_dir("scenes")
    except FileNotFoundError as exc:
        assert "reinstall" in str(exc)  # noqa: PT017 -- the else: branch fails the test
    else:
        raise AssertionError("a foreign scenes/ folder was taken for solas-mi's")


def test_shipped_lenses_are_found():
    names = {p.stem for p in (resources.resource_dir("scenes") / "lenses").glob("*.toml")}
    assert {"solas_doublet", "cooke_triplet"} <= names


def test_version_comes_from_the_installed_metadata():
    from importlib.metadata import version

    import solas_mi

    assert solas_mi.__version__ == version("solas-mi")
