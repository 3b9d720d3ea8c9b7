"""The TOML settings reader (``mvtrack.config.load_config``) under fuzzing.

Any document, valid TOML or not, must give a :class:`RunSettings` or an :class:`InputError`
of one line naming the file; and settings written as TOML must read back as they were.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mvtrack.config import RunSettings, load_config
from mvtrack.errors import InputError
from mvtrack.registry import DETECTORS
from mvtrack.tracking import TrackerConfig

EXAMPLES = int(os.environ.get("MVTRACK_FUZZ_EXAMPLES", "60"))
FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=os.environ.get("CI", "").lower() == "true",
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
TRACKER_FIELDS = sorted(f.name for f in dataclasses.fields(TrackerConfig))
SAFE_TEXT = st.text(
    st.characters(codec="utf-8", exclude_categories=("Cc", "Cs")), max_size=8
)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(k)} = {_toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(value)  # pragma: no cover


def _key(key: str) -> str:
    return json.dumps(key, ensure_ascii=False)


def _toml(doc: dict[str, Any]) -> str:
    """TOML text of ``doc``: top-level scalars first, then one ``[table]`` per dict."""
    lines = [f"{_key(k)} = {_toml_value(v)}" for k, v in doc.items() if not isinstance(v, dict)]
    for name, table in doc.items():
        if isinstance(table, dict):
            lines.append(f"[{_key(name)}]")
            lines += [f"{_key(k)} = {_toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


scalars = st.one_of(
    st.booleans(), st.integers(-(2**63), 2**63 - 1), st.floats(), SAFE_TEXT,
    st.sampled_from(["default", "paper1", "paper2", *DETECTORS, "kalman-ca", "rls"]),
)
values = st.recursive(
    scalars,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(SAFE_TEXT, inner, max_size=3),
    max_leaves=6,
)
known_keys = st.sampled_from([
    *TRACKER_FIELDS, "preset", "name", "enabled", "write", "trail", "gates", "threshold",
])
tables = st.dictionaries(known_keys | SAFE_TEXT, values, max_size=5)
documents = st.dictionaries(
    st.sampled_from(["tracker", "detector", "templates", "video"]) | SAFE_TEXT,
    tables | values,
    max_size=5,
)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("toml")


def _load(path: Path) -> RunSettings | None:
    try:
        return load_config(path)
    except InputError as exc:
        message = str(exc)
        assert "\n" not in message and str(path) in message, message
        return None


valid_settings = st.builds(
    RunSettings,
    tracker=st.dictionaries(st.sampled_from(TRACKER_FIELDS), scalars, max_size=4).filter(
        lambda d: "gate" not in d or type(d["gate"]) in (int, float)  # a number, not a bool
    ),
    detector=st.sampled_from(tuple(DETECTORS)),
    detector_params=st.dictionaries(
        st.sampled_from(["threshold", "min_area"]), scalars, max_size=2
    ),
    templates=st.booleans(),
    template_params=st.dictionaries(st.sampled_from(["size", "threshold"]), scalars, max_size=2),
    video=st.booleans(),
    trail=st.integers(2, 10**6),
    gates=st.booleans(),
)


def _document(want: RunSettings) -> dict[str, Any]:
    """The TOML tables that stand for ``want``."""
    return {
        "tracker": dict(want.tracker),
        "detector": {"name": want.detector, **want.detector_params},
        "templates": {"enabled": want.templates, **want.template_params},
        "video": {"write": want.video, "trail": want.trail, "gates": want.gates},
    }


@st.composite
def near_valid(draw: st.DrawFn) -> dict[str, Any]:
    """A valid document with one table, key or value replaced by anything."""
    doc = _document(draw(valid_settings))
    name = draw(st.sampled_from([*doc, "extra"]))
    what = draw(st.sampled_from(["value", "key", "table"]))
    if what == "table" or name not in doc:
        doc[name] = draw(tables | values)
    elif what == "key":
        doc[name][draw(known_keys | SAFE_TEXT)] = draw(values)
    elif doc[name]:
        doc[name][draw(st.sampled_from(sorted(doc[name])))] = draw(values)
    return doc


@FUZZ
@given(doc=documents | near_valid())
def test_any_document_loads_or_fails_with_one_line(workdir: Path, doc: dict[str, Any]) -> None:
    path = workdir / "doc.toml"
    path.write_text(_toml(doc), encoding="utf-8")
    got = _load(path)
    if got is not None:
        assert got.detector in DETECTORS and got.trail >= 2
        assert isinstance(got.video, bool) and isinstance(got.templates, bool)


@FUZZ
@given(raw=st.binary(max_size=200) | st.text(max_size=200).map(str.encode))
def test_any_bytes_load_or_fail_with_one_line(workdir: Path, raw: bytes) -> None:
    path = workdir / "raw.toml"
    path.write_bytes(raw)
    _load(path)


def _same(a: Any, b: Any) -> bool:
    """Equal, with NaN equal to NaN."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    return type(a) is type(b) and a == b


@FUZZ
@given(want=valid_settings)
def test_settings_written_as_toml_read_back(workdir: Path, want: RunSettings) -> None:
    """Settings of the right shape read back as they were, or (a value the tracker, the front
    end or the template bank refuses, checked when the file is read) are refused in one line
    naming the file and the table or key."""
    path = workdir / "valid.toml"
    path.write_text(_toml(_document(want)), encoding="utf-8")
    try:
        got = load_config(path)
    except InputError as exc:
        message = str(exc)
        assert "\n" not in message and str(path) in message, message
        named = [f"tracker.{k}" for k in want.tracker] + [
            f"detector.{k}" for k in want.detector_params] + [
            f"templates.{k}" for k in want.template_params] + [
            "[tracker]", "detector ", "template settings"]
        assert any(n in message for n in named), message
        return
    assert _same(got.as_dict(), want.as_dict())
