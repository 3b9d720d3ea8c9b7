"""The compiled kernels: every module that defines one is hashed into the cache folder, so an
edit to any kernel (or to a kernel it calls) moves the cache and nothing needs deleting."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

import mvtrack
from mvtrack import jit

PACKAGE = Path(mvtrack.__file__).resolve().parent


def test_every_module_with_a_kernel_is_hashed() -> None:
    defining = {
        str(p.relative_to(PACKAGE))
        for p in PACKAGE.rglob("*.py")
        if re.search(r"^@kernel$", p.read_text(), flags=re.M)
    }
    assert defining  # the tracker has kernels
    assert defining <= set(jit.KERNEL_MODULES)


def test_the_cache_folder_follows_the_kernels_source(tmp_path: Path, monkeypatch) -> None:
    copy = tmp_path / "pkg"
    for name in jit.KERNEL_MODULES:
        (copy / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(PACKAGE / name, copy / name)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    monkeypatch.setattr(jit, "_PACKAGE", copy)
    monkeypatch.setattr(jit, "_cache", None)
    first = jit.cache_dir()
    assert first is not None and Path(first).is_dir()
    assert Path(first).parent == tmp_path / "cache" / "mvtrack"
    monkeypatch.setattr(jit, "_cache", None)
    assert jit.cache_dir() == first  # the same sources, the same folder
    step = copy / "tracking" / "step.py"
    step.write_text(step.read_text() + "\n# an edit\n")
    monkeypatch.setattr(jit, "_cache", None)
    assert jit.cache_dir() != first


def test_a_kernel_keeps_its_plain_function() -> None:
    if not jit.COMPILED:
        pytest.skip("numba is not compiling here")
    from mvtrack.tracking.lifecycle import births

    assert births.py_func is not births and callable(births.py_func)


def _add_one(x: float) -> float:
    return x + 1.0


def _fresh_kernel(monkeypatch, folder: Path):  # type: ignore[no-untyped-def]
    """``_add_one`` compiled with a cache folder of its own, so its first call compiles."""
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setattr(jit, "_cache", str(folder))
    return jit.kernel(_add_one)


def test_the_first_compile_is_announced_once_and_a_cache_load_not_at_all(
    tmp_path: Path, monkeypatch
) -> None:
    if not jit.COMPILED:
        pytest.skip("numba is not compiling here")
    calls: list[int] = []
    jit.on_first_compile(lambda: calls.append(1))
    monkeypatch.setattr(jit, "_compiled", False)
    add = _fresh_kernel(monkeypatch, tmp_path)
    assert not jit.compiled_here()
    assert add(1.0) == 2.0 and calls == [1]  # compiled: announced
    assert jit.compiled_here()
    assert add(2) == 3.0 and calls == [1]  # a second specialisation: not again
    jit.on_first_compile(lambda: calls.append(2))
    again = _fresh_kernel(monkeypatch, tmp_path)  # the same function, a new dispatcher
    assert again(1.0) == 2.0 and calls == [1]  # loaded from the cache: nothing to say
    jit.on_first_compile(lambda: None)  # leave no test callback behind


def test_the_command_line_says_it_is_compiling(tmp_path: Path, monkeypatch, capsys) -> None:
    if not jit.COMPILED:
        pytest.skip("numba is not compiling here")
    from mvtrack.cli import main

    assert main(["--version"]) == 0
    capsys.readouterr()
    _fresh_kernel(monkeypatch, tmp_path)(1.0)
    err = capsys.readouterr().err
    assert "compiling mvtrack's kernels" in err and err.count("\n") == 1
    from mvtrack.cli._options import speed_note

    assert speed_note() == "; this first run includes compiling the kernels"
    monkeypatch.setattr(jit, "_compiled", False)
    assert speed_note() == ""
