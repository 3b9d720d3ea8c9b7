"""Analytics settings from the ``[analytics]`` table of a TOML file.

The same file may hold the tracker's tables (``[tracker]``, ``[detector]``, ``[templates]``,
``[video]``, see :mod:`mvtrack.config`); this module reads ``[analytics]`` and its sub-tables
and ignores those. Every key is checked: an unknown key, a wrong type or an absurd value is
an :class:`~mvtrack.errors.InputError` of one line naming the file and the key, e.g.
``scene.toml: analytics.lines.north.points must be two [x, y] points``. Example:
``docs/analytics-example.toml``.
"""

from __future__ import annotations

import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mvtrack.analytics.calibration import GroundCalibration
from mvtrack.analytics.lines import CountLine
from mvtrack.analytics.movements import MovementSettings
from mvtrack.analytics.speed import VELOCITIES, SpeedSettings
from mvtrack.analytics.tracks import ANCHORS
from mvtrack.analytics.zones import Zone
from mvtrack.config import TABLES
from mvtrack.errors import InputError

#: tables the tracker reads from the same file (mvtrack.config)
ENGINE_TABLES = tuple(t for t in TABLES if t != "analytics")
_TOP = ("interval", "fps", "anchor", "min_frames", "calibration", "speed", "movements",
        "lines", "zones", "approaches")
_UNITS = {"s": 1.0, "sec": 1.0, "min": 60.0, "h": 3600.0}


@dataclass(frozen=True)
class AnalyticsSettings:
    """Everything the analytics need besides the tracks.

    Attributes
    ----------
    lines, zones, approaches : tuple
        Count lines, zones (occupancy, dwell) and the approaches of an intersection
        (turning movements).
    calibration : GroundCalibration or None
        Image → ground map; without it there are no speeds.
    interval : float
        Length of a counting interval, seconds (default 15 min).
    fps : float or None
        Frame rate (default: the run's ``summary.json``).
    anchor : {"centre", "foot"}
        The point of the box that counts on lines and in zones.
    min_frames : int
        Tracks with fewer rows are left out of every count (and reported as such).
    speed, movements : SpeedSettings, MovementSettings
    """

    lines: tuple[CountLine, ...] = ()
    zones: tuple[Zone, ...] = ()
    approaches: tuple[Zone, ...] = ()
    calibration: GroundCalibration | None = None
    interval: float = 900.0
    fps: float | None = None
    anchor: str = "centre"
    min_frames: int = 5
    speed: SpeedSettings = field(default_factory=SpeedSettings)
    movements: MovementSettings = field(default_factory=MovementSettings)


def _dotted(key: str) -> str:
    return f"analytics.{key}" if key else "analytics"


class _Checker:
    """Type checks that name the file and the dotted key."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, key: str, problem: str) -> InputError:
        return InputError(f"{self.path}: {_dotted(key)} {problem}")

    def table(self, key: str, value: Any, known: tuple[str, ...] | None = None) -> dict[str, Any]:
        if not isinstance(value, dict):
            raise self.fail(key, f"must be a table ([{_dotted(key)}]), got {value!r}")
        if known is not None:
            for k in value:
                if k not in known:
                    raise InputError(f"{self.path}: unknown key '{_dotted(key)}.{k}' "
                                     f"(known: {', '.join(known)})")
        return value

    def number(self, key: str, value: Any, *, positive: bool = False,
               minimum: float | None = None) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(
                value):
            raise self.fail(key, f"must be a number, got {value!r}")
        if positive and not value > 0:
            raise self.fail(key, f"must be > 0, got {value!r}")
        if minimum is not None and value < minimum:
            raise self.fail(key, f"must be >= {minimum:g}, got {value!r}")
        return float(value)

    def points(self, key: str, value: Any, n: int | None = None,
               at_least: int | None = None) -> list[list[float]]:
        what = f"{n} [x, y] points" if n else f"a list of at least {at_least} [x, y] points"
        ok = isinstance(value, list) and all(
            isinstance(p, list) and len(p) == 2 and all(
                isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
                for c in p) for p in value)
        if not ok or (n is not None and len(value) != n) or (
                at_least is not None and len(value) < at_least):
            raise self.fail(key, f"must be {what}, got {value!r}")
        return [[float(c) for c in p] for p in value]

    def string(self, key: str, value: Any, choices: tuple[str, ...] | None = None) -> str:
        if not isinstance(value, str):
            raise self.fail(key, f"must be a string, got {value!r}")
        if choices is not None and value not in choices:
            raise self.fail(key, f"must be one of {', '.join(choices)}, got {value!r}")
        return value


def parse_duration(text: str | float | int) -> float:
    """``900``, ``"900s"``, ``"15min"``, ``"1h"`` → seconds."""
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        return float(text)
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*([a-z]*)\s*", str(text).lower())
    if not m or m.group(2) not in ("", *_UNITS):
        raise ValueError(f"not a duration: {text!r} (use seconds, or e.g. '15min', '1h')")
    return float(m.group(1)) * _UNITS.get(m.group(2), 1.0)


def settings_from_dict(data: dict[str, Any], path: str | os.PathLike[str] = "<settings>"
                       ) -> AnalyticsSettings:
    """Build :class:`AnalyticsSettings` from the ``[analytics]`` table (already parsed)."""
    c = _Checker(Path(path))
    data = c.table("", data, _TOP) if data else {}
    kw: dict[str, Any] = {}
    if "interval" in data:
        try:
            kw["interval"] = parse_duration(data["interval"])
        except ValueError as exc:
            raise c.fail("interval", f"is {exc}") from None
        if not (math.isfinite(kw["interval"]) and kw["interval"] > 0):
            raise c.fail("interval", f"must be > 0, got {data['interval']!r}")
    if "fps" in data:
        kw["fps"] = c.number("fps", data["fps"], positive=True)
    if "anchor" in data:
        kw["anchor"] = c.string("anchor", data["anchor"], ANCHORS)
    if "min_frames" in data:
        v = data["min_frames"]
        if isinstance(v, bool) or not isinstance(v, int) or v < 1:
            raise c.fail("min_frames", f"must be an integer >= 1, got {v!r}")
        kw["min_frames"] = v

    if "calibration" in data:
        cal = c.table("calibration", data["calibration"], ("image", "ground",
                                                            "metres_per_pixel"))
        if "metres_per_pixel" in cal:
            if "image" in cal or "ground" in cal:
                raise c.fail("calibration", "takes either metres_per_pixel or image + ground "
                                            "points, not both")
            kw["calibration"] = GroundCalibration.from_scale(
                c.number("calibration.metres_per_pixel", cal["metres_per_pixel"],
                         positive=True))
        elif "image" in cal and "ground" in cal:
            img = c.points("calibration.image", cal["image"], at_least=4)
            gnd = c.points("calibration.ground", cal["ground"], at_least=4)
            try:
                kw["calibration"] = GroundCalibration.from_points(img, gnd)
            except ValueError as exc:
                raise InputError(f"{c.path}: analytics.{exc}") from None
        else:
            raise c.fail("calibration", "needs metres_per_pixel, or both image and ground "
                                        "(four or more point pairs)")

    if "speed" in data:
        sp = c.table("speed", data["speed"], ("smooth", "stop_z", "stop_max", "stop_min",
                                               "anchor", "velocity"))
        skw: dict[str, Any] = {}
        for key in ("smooth", "stop_z", "stop_max", "stop_min"):
            if key in sp:
                skw[key] = c.number(f"speed.{key}", sp[key], positive=key == "smooth",
                                    minimum=0.0)
        if "anchor" in sp:
            skw["anchor"] = c.string("speed.anchor", sp["anchor"], ANCHORS)
        if "velocity" in sp:
            skw["velocity"] = c.string("speed.velocity", sp["velocity"], VELOCITIES)
        kw["speed"] = SpeedSettings(**skw)

    if "movements" in data:
        mv = c.table("movements", data["movements"],
                     ("horizon", "window", "gap", "min_speed", "max_turn",
                      "centre", "join", "join_radius"))
        mkw: dict[str, Any] = {}
        for key in ("horizon", "window", "gap", "min_speed", "max_turn", "join",
                    "join_radius"):
            if key in mv:
                mkw[key] = c.number(f"movements.{key}", mv[key], minimum=0.0)
        if "centre" in mv:
            mkw["centre"] = tuple(c.points("movements.centre", [mv["centre"]], 1)[0])
        kw["movements"] = MovementSettings(**mkw)

    names: set[str] = set()
    for group in ("lines", "zones", "approaches"):
        if group not in data:
            continue
        table = c.table(group, data[group])
        items = []
        for name, spec in table.items():
            key = f"{group}.{name}"
            if group == "lines":
                spec = c.table(key, spec, ("points", "hysteresis", "labels"))
                if "points" not in spec:
                    raise c.fail(key, "needs points = [[x1, y1], [x2, y2]]")
                pts = c.points(f"{key}.points", spec["points"], 2)
                hyst = c.number(f"{key}.hysteresis", spec.get("hysteresis", 4.0), minimum=0.0)
                labels = spec.get("labels", ["forward", "backward"])
                if not (isinstance(labels, list) and len(labels) == 2 and all(
                        isinstance(s, str) and s for s in labels) and labels[0] != labels[1]):
                    raise c.fail(f"{key}.labels", f"must be two different names, got {labels!r}")
                try:
                    items.append(CountLine(name, pts[0], pts[1], hyst, tuple(labels)))
                except ValueError as exc:
                    raise c.fail(key, f"is invalid: {exc}") from None
            else:
                spec = c.table(key, spec, ("polygon",))
                if "polygon" not in spec:
                    raise c.fail(key, "needs polygon = [[x, y], ...] (3 or more points)")
                poly = c.points(f"{key}.polygon", spec["polygon"], at_least=3)
                try:
                    items.append(Zone(name, poly))
                except ValueError as exc:
                    raise c.fail(key, f"is invalid: {exc}") from None
            if group != "approaches":
                if name in names:
                    raise c.fail(key, "has the name of another line or zone")
                names.add(name)
        kw[group] = tuple(items)
    if len(kw.get("approaches", ())) == 1:
        raise c.fail("approaches", "needs at least two approaches for turning movements")
    return AnalyticsSettings(**kw)


def read_table(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The ``[analytics]`` table of a TOML file (empty when it has none), the other tables
    checked to be the tracker's.

    Raises
    ------
    InputError
        Missing or unreadable file, invalid TOML, an unknown table (one line).
    """
    path = Path(path)
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise InputError(f"settings file not found: {path}") from None
    except IsADirectoryError:
        raise InputError(f"settings path is a folder, not a file: {path}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: invalid TOML: {str(exc).splitlines()[0]}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read settings file {path}: {exc}") from None
    for key in data:
        if key != "analytics" and key not in ENGINE_TABLES:
            raise InputError(f"{path}: unknown table {key!r} (known: analytics, "
                             f"{', '.join(ENGINE_TABLES)})")
    table = data.get("analytics", {})
    if not isinstance(table, dict):
        raise InputError(f"{path}: analytics must be a table ([analytics]), got {table!r}")
    return table


def load_settings(path: str | os.PathLike[str]) -> AnalyticsSettings:
    """Read the ``[analytics]`` table of a TOML file (module docstring).

    Raises
    ------
    InputError
        Missing or unreadable file, invalid TOML, an unknown table or key, a wrong type or
        value (one line naming the file and the key).
    """
    return settings_from_dict(read_table(path), path)
