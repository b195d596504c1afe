from solas_mi import resources


def test_checkout_layout_first_then_installed(tmp_path, monkeypatch):
    package = tmp_path / "site" / "solas_mi"
    (package / "scenes" / "lenses").mkdir(parents=True)
    monkeypatch.setattr(resources, "_PACKAGE", package)
    assert resources.resource_dir("scenes") == package / "scenes"  # wheel: inside the package
    (tmp_path / "site" / "scenes").mkdir()
    assert resources.resource_dir("scenes") == tmp_path / "site" / "scenes"  # checkout: beside it


def test_shipped_lenses_are_found():
    names = {p.stem for p in (resources.resource_dir("scenes") / "lenses").glob("*.toml")}
    assert {"solas_doublet", "cooke_triplet"} <= names
