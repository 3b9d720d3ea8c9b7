"""Settings of a video tracking run, from a TOML file (``--config FILE.toml``) and the CLI.

The file has six optional tables; every key is optional and the command-line options win
over the file::

    [tracker]                 # preset, then any field of mvtrack.tracking.TrackerConfig
    preset = "paper1"         # "default", "paper1" or "paper2"
    predictor = "rls"
    gate = 10.0
    birth_iou = "none"        # TOML has no null: "none" unsets a field (turns a rule off)

    [detector]                # the front end, then its parameters
    name = "disturbance-map"
    threshold = 25

    [templates]               # template matching for stopped vehicles (paper 1 §1.1 step 3)
    enabled = true            # then any parameter of mvtrack.detection.template.TemplateBank

    [video]                   # the annotated MP4
    write = true
    trail = 30                # frames of trail behind each track
    gates = true              # draw the gate regions

    [relink]                  # a track ended behind an occluder continued by a new one
    enabled = true            # then any field of RelinkSettings (below)
    window = 2.0              # seconds

    [analytics]               # counts, movements and speeds (mvtrack.analytics.settings)
    interval = "15min"        # with sub-tables [analytics.lines.NAME], [analytics.zones.NAME],
                              # [analytics.approaches.NAME], [analytics.calibration], ...

With an ``[analytics]`` table, ``mvtrack track`` also writes ``counts.csv``, ``movements.csv``,
``speeds.csv`` and ``tracks.csv`` beside ``results.txt`` (see ``docs/analytics-example.toml``).

An unknown table or key is an :class:`~mvtrack.errors.InputError` naming the file and key, so a
misspelt setting never passes silently. Tracker keys are checked against ``TrackerConfig``'s
fields, detector and template keys against the constructor of the front end / template bank
when those are built (:mod:`mvtrack.video.build`).
"""

from __future__ import annotations

import dataclasses
import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mvtrack.errors import InputError
from mvtrack.registry import DEFAULT_DETECTOR, DETECTORS


@dataclasses.dataclass(frozen=True)
class RelinkSettings:
    """The ``[relink]`` table: how the video loop continues a track that ended behind an
    occluder (:mod:`mvtrack.video.relink`).

    Attributes
    ----------
    enabled : bool
        Relink at all.
    window : float
        Seconds after its end during which a track can be continued.
    reach : float
        Radius of the motion test as a share of the taller box, at the ended track's last
        row.
    spread : float
        Growth of that radius per second since the ended track's last row, as a share of the
        taller box: where a hidden walker is becomes less certain the longer it is hidden (it
        may slow down, stop or turn back; half a body height a second is about a third of a
        walker's speed).
    min_similarity : float
        Least Bhattacharyya coefficient of the appearances, in [0, 1].
    size_ratio : float
        Largest ratio of the two box heights (> 1).
    smoothing : float
        Weight in (0, 1] of a new measured box in the appearance's exponential average.
    """

    enabled: bool = True
    window: float = 2.0
    reach: float = 0.5
    min_similarity: float = 0.8
    size_ratio: float = 1.6
    smoothing: float = 0.1
    spread: float = 0.5

    def __post_init__(self) -> None:
        ranges = {  # name: the test of a number
            "spread": lambda v: v >= 0,
            "window": lambda v: v > 0, "reach": lambda v: v > 0,
            "min_similarity": lambda v: 0.0 <= v <= 1.0,
            "size_ratio": lambda v: v > 1.0, "smoothing": lambda v: 0.0 < v <= 1.0,
        }
        for name, ok in ranges.items():
            value = getattr(self, name)
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            if not number or not math.isfinite(value) or not ok(value):
                raise ValueError(f"relink.{name} is out of range (got {value!r})")
        if not isinstance(self.enabled, bool):
            raise ValueError(f"relink.enabled must be true or false (got {self.enabled!r})")


def relink_settings(table: dict[str, Any] | None) -> RelinkSettings:
    """:class:`RelinkSettings` from a ``[relink]`` table (``None``: the defaults)."""
    if not table:
        return RelinkSettings()
    known = {f.name for f in dataclasses.fields(RelinkSettings)}
    unknown = sorted(set(table) - known)
    if unknown:
        raise ValueError(f"relink: unknown key {', '.join(map(repr, unknown))} (known: "
                         f"{', '.join(sorted(known))})")
    return RelinkSettings(**table)

_TABLES: dict[str, tuple[str, ...]] = {
    "tracker": (),  # checked against TrackerConfig fields (plus "preset")
    "detector": (),  # "name" plus the detector's parameters
    "templates": (),  # "enabled" plus TemplateBank parameters
    "video": ("write", "trail", "gates"),
    "relink": (),  # checked against RelinkSettings
    "analytics": (),  # checked by mvtrack.analytics.settings
}


@dataclass(frozen=True)
class RunSettings:
    """Everything ``mvtrack track`` needs besides the video.

    Attributes
    ----------
    tracker : dict
        ``preset`` (optional) and overrides of ``TrackerConfig`` fields.
    detector : str
        Front-end name (one of :data:`mvtrack.registry.DETECTORS`).
    detector_params : dict
        Keyword arguments of the front end.
    templates : bool
        Keep a template bank and rescue stopped vehicles by template matching.
    template_params : dict
        Keyword arguments of the template bank.
    video : bool
        Write the annotated MP4.
    trail : int
        Frames of trail drawn behind each track.
    gates : bool
        Draw the gate regions in the annotated video.
    analytics : dict or None
        The ``[analytics]`` table as read (already checked by
        :func:`mvtrack.analytics.settings.settings_from_dict`); None when the file has none.
    relink : RelinkSettings
        Whether and how a new track continues one that ended behind an occluder
        (:mod:`mvtrack.video.relink`).
    """

    tracker: dict[str, Any] = field(default_factory=dict)
    detector: str = DEFAULT_DETECTOR
    detector_params: dict[str, Any] = field(default_factory=dict)
    templates: bool = True
    template_params: dict[str, Any] = field(default_factory=dict)
    video: bool = True
    trail: int = 30
    gates: bool = True
    analytics: dict[str, Any] | None = None
    relink: RelinkSettings = field(default_factory=RelinkSettings)

    def with_overrides(self, **tracker_overrides: Any) -> RunSettings:
        """A copy with the non-None ``tracker_overrides`` (CLI options) applied."""
        tracker = dict(self.tracker)
        tracker.update({k: v for k, v in tracker_overrides.items() if v is not None})
        return dataclasses.replace(self, tracker=tracker)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready form (for ``summary.json``)."""
        return dataclasses.asdict(self)


def _tracker_fields() -> set[str] | None:
    """Field names of ``TrackerConfig``, or None when the tracker is not importable."""
    try:
        from mvtrack.tracking import TrackerConfig
    except ImportError:  # pragma: no cover - only while the tracker is missing
        return None
    return {f.name for f in dataclasses.fields(TrackerConfig)}


def _unknown(path: Path, key: str, known: set[str] | tuple[str, ...]) -> InputError:
    return InputError(
        f"{path}: unknown key {key!r} (known: {', '.join(sorted(known))})"
    )


def _check_type(path: Path, key: str, value: Any, kind: type | tuple[type, ...]) -> None:
    if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
        names = kind.__name__ if isinstance(kind, type) else "/".join(k.__name__ for k in kind)
        raise InputError(f"{path}: {key} must be {names}, got {value!r}")


def load_config(path: str | os.PathLike[str]) -> RunSettings:
    """Read a TOML settings file.

    Raises
    ------
    InputError
        If the file is missing or not valid TOML, or holds an unknown table or key or a value of
        the wrong type. The message is one line naming the file and the key.
    """
    path = Path(path)
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise InputError(f"config file not found: {path}") from None
    except IsADirectoryError:
        raise InputError(f"config path is a folder, not a file: {path}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: invalid TOML: {str(exc).splitlines()[0]}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read config file {path}: {exc}") from None

    for key, value in data.items():
        if key not in _TABLES:
            raise _unknown(path, key, tuple(_TABLES))
        if not isinstance(value, dict):
            raise InputError(f"{path}: {key} must be a table ([{key}]), got {value!r}")

    tracker = dict(data.get("tracker", {}))
    known = _tracker_fields()
    if known is not None:
        for key in tracker:
            if key != "preset" and key not in known:
                raise _unknown(path, f"tracker.{key}", known | {"preset"})
    if "preset" in tracker:
        _check_type(path, "tracker.preset", tracker["preset"], str)
    if "gate" in tracker:
        _check_type(path, "tracker.gate", tracker["gate"], (int, float))

    detector_table = dict(data.get("detector", {}))
    name = detector_table.pop("name", RunSettings.detector)
    _check_type(path, "detector.name", name, str)
    if name not in DETECTORS:
        raise InputError(
            f"{path}: detector.name {name!r} is not a detector (choose one of: "
            f"{', '.join(DETECTORS)})"
        )

    template_table = dict(data.get("templates", {}))
    enabled = template_table.pop("enabled", True)
    _check_type(path, "templates.enabled", enabled, bool)

    video_table = data.get("video", {})
    for key in video_table:
        if key not in _TABLES["video"]:
            raise _unknown(path, f"video.{key}", _TABLES["video"])
    write = video_table.get("write", True)
    trail = video_table.get("trail", RunSettings.trail)
    gates = video_table.get("gates", True)
    _check_type(path, "video.write", write, bool)
    _check_type(path, "video.trail", trail, int)
    _check_type(path, "video.gates", gates, bool)
    if trail < 2:
        raise InputError(f"{path}: video.trail must be at least 2, got {trail}")

    analytics = data.get("analytics")
    if analytics is not None:
        from mvtrack.analytics.settings import settings_from_dict

        settings_from_dict(analytics, path)  # every key checked now, before any tracking

    relink_table = data.get("relink")
    if relink_table is not None and not isinstance(relink_table, dict):
        raise InputError(f"{path}: [relink] must be a table")
    try:
        relink = relink_settings(relink_table)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{path}: {exc}") from None

    return RunSettings(
        tracker=tracker,
        detector=name,
        detector_params=detector_table,
        templates=enabled,
        template_params=template_table,
        video=write,
        trail=trail,
        gates=gates,
        analytics=analytics,
        relink=relink,
    )
