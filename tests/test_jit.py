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
