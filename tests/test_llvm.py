import pytest

from solas_mi import SolasError, llvm


def _fake_libs(tmp_path, monkeypatch, names):
    for name in names:
        (tmp_path / name).write_bytes(b"")
    monkeypatch.setattr(llvm, "_SEARCH", (str(tmp_path / "libLLVM*.so*"),))
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)


def test_picks_newest_usable(tmp_path, monkeypatch):
    _fake_libs(tmp_path, monkeypatch, ["libLLVM-15.so", "libLLVM.so.19.1", "libLLVM-17.so"])
    assert llvm.select_libllvm().endswith("libLLVM.so.19.1")


def test_only_old_llvm_fails_clearly(tmp_path, monkeypatch):
    _fake_libs(tmp_path, monkeypatch, ["libLLVM-14.so", "libLLVM-15.so.1", "libLLVM-16.so"])
    with pytest.raises(
        SolasError, match=r"Dr.Jit needs libLLVM >= 17; found: 14 .*15 .*16 .*apt-get install -y libllvm19"
    ):
        llvm.select_libllvm()


def test_explicit_old_path_is_refused(tmp_path, monkeypatch):
    old = tmp_path / "libLLVM-15.so"
    old.write_bytes(b"")
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", str(old))
    with pytest.raises(SolasError, match="is libLLVM 15; Dr.Jit needs libLLVM >= 17"):
        llvm.select_libllvm()


@pytest.mark.parametrize(
    "path, version",
    [
        ("/usr/lib/llvm-19/lib/libLLVM.so.1", 19),
        ("/usr/lib/x86_64-linux-gnu/libLLVM-15.so.1", 15),
        ("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1", 19),
        ("/usr/lib/llvm-14/lib/libLLVM-14.so", 14),
    ],
)
def test_version_of_library_path(path, version):
    assert llvm.libllvm_version(path) == version
