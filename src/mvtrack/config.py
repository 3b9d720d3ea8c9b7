"""Settings of a video tracking run, from a TOML file (``--config FILE.toml``) and the CLI.

The file has six optional tables; every key is optional and the command-line options win
over the file::

    [tracker]                 # preset, then any field of mvtrack.tracking.TrackerConfig
    preset = "paper1"         # "default", "paper1" or "paper2"
    predictor = "rls"
    fps = 10                  # the source's frame rate, as --fps (the option wins)
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

``mvtrack config --show`` prints every setting with its default (:func:`default_toml`);
``docs/config.md`` explains the file.

An unknown table or key, or a value of the wrong type or out of range, is an
:class:`~mvtrack.errors.InputError` of one line naming the file and the key (``scene.toml:
tracker.max_misses must be ...``), so a misspelt setting never passes silently. Tracker keys are
checked against ``TrackerConfig``'s fields and by building the tracker once; detector and
template keys against the parameters (and their annotated types) of the front end's and the
template bank's constructors.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import os
import re
import tomllib
from collections.abc import Callable, Mapping
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

#: the tables of a settings file, and the keys of those whose keys are fixed
TABLES: dict[str, tuple[str, ...]] = {
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
    coasting : bool
        Also write the rows of coasting tracks (no detection, while the tracker's prediction
        is within ``coast_std`` box sizes) to ``results.txt``: ``--coasting``, no key in the
        file.
    offline : bool
        Revise the rows once the whole video is tracked: each confirmed track written from
        its first detection and smoothed over all of them (:mod:`mvtrack.video.offline`):
        ``--offline``, no key in the file.
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
    coasting: bool = False
    offline: bool = False

    def with_overrides(self, **tracker_overrides: Any) -> RunSettings:
        """A copy with the non-None ``tracker_overrides`` (CLI options) applied."""
        tracker = dict(self.tracker)
        tracker.update({k: v for k, v in tracker_overrides.items() if v is not None})
        return dataclasses.replace(self, tracker=tracker)

    @property
    def frame_rate(self) -> float | None:
        """The frame rate the settings give the run (``[tracker] fps``, or ``--fps``), or None
        for the source's own."""
        fps = self.tracker.get("fps")
        return float(fps) if _is_number(fps) else None

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready form (for ``summary.json``)."""
        return dataclasses.asdict(self)


#: the highest frame rate a source may be given, frames per second (a fast camera)
MAX_FPS = 1000.0


def _is_number(value: Any) -> bool:
    return (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value))


def check_fps(name: str, value: Any) -> float:
    """``value`` as a frame rate, or an :class:`InputError` naming the setting ``name``
    (``--fps``, ``scene.toml: tracker.fps``): a finite number in (0, :data:`MAX_FPS`]."""
    if not _is_number(value) or not 0.0 < value <= MAX_FPS:
        raise InputError(f"{name} must be a frame rate above 0 and at most {MAX_FPS:g} frames "
                         f"per second, got {value!r}")
    return float(value)


def tracker_error(exc: Exception, name_of: Callable[[str], str], context: str) -> InputError:
    """The tracker's message of ``exc`` with each ``TrackerConfig.<field>`` named as the user
    gave the setting (``name_of(field)``: an option or a file's key); a message that names
    no field is prefixed with ``context``."""
    text = str(exc).removeprefix("tracker settings: ")
    named, n = re.subn(r"TrackerConfig\.(\w+)", lambda m: name_of(m.group(1)), text)
    return InputError(named if n else f"{context}: {text}")


def check_tracker(tracker: Mapping[str, Any], name_of: Callable[[str], str],
                  context: str = "tracker settings") -> None:
    """Build the tracker of the ``[tracker]`` settings ``tracker`` once, so a bad value stops
    the command before any work, in one line naming the setting as the user gave it.

    Parameters
    ----------
    tracker : mapping
        ``preset`` and ``TrackerConfig`` fields (``"none"`` for None), as in
        :attr:`RunSettings.tracker`.
    name_of : callable
        The user's name of a field: ``"--score-high"``, ``"scene.toml: tracker.gate"``.
    context : str
        Prefix of a message that names no field.

    Raises
    ------
    InputError
        An unknown predictor, distance, assignment rule or preset, a bad frame rate, or a
        value ``TrackerConfig`` refuses.
    """
    from mvtrack.registry import ASSIGN_RULES, DISTANCES, PREDICTORS
    from mvtrack.tracking import PRESETS
    from mvtrack.video.build import build_tracker

    for key, known, what in (("preset", PRESETS, "tracker preset"),
                             ("predictor", PREDICTORS, "predictor"),
                             ("distance", DISTANCES, "distance"),
                             ("assign", ASSIGN_RULES, "assignment rule")):
        value = tracker.get(key)
        if value is not None and (not isinstance(value, str) or value not in known):
            raise InputError(f"{name_of(key)} {value!r} is not a {what} (choose one of: "
                             f"{', '.join(known)})")
    if "fps" in tracker:
        check_fps(name_of("fps"), tracker["fps"])
    try:
        build_tracker(RunSettings(tracker=dict(tracker)), 30.0)
    except (TypeError, ValueError) as exc:
        raise tracker_error(exc, name_of, context) from None


def _signature_types(targets: list[Callable[..., Any]]) -> dict[str, str]:
    """Parameter name -> annotation text of the keyword parameters of ``targets``."""
    types: dict[str, str] = {}
    for target in targets:
        for p in inspect.signature(target).parameters.values():
            if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL) and isinstance(p.annotation, str):
                types.setdefault(p.name, p.annotation)
    return types


def detector_signatures(name: str) -> list[Callable[..., Any]]:
    """The constructors whose parameters a ``[detector]`` table of front end ``name`` sets."""
    from mvtrack.registry import DETECTORS, load

    cls = load(DETECTORS[name])
    targets = [cls]
    if any(p.kind == p.VAR_KEYWORD for p in inspect.signature(cls).parameters.values()):
        from mvtrack.detection.blobs import BlobExtractor  # a front end's **blob parameters

        targets.append(BlobExtractor)
    return targets


def template_signatures() -> list[Callable[..., Any]]:
    """The constructors whose parameters a ``[templates]`` table sets."""
    from mvtrack.detection.template import TemplateBank
    from mvtrack.video.rescue import StoppedVehicleRescuer

    return [TemplateBank, StoppedVehicleRescuer.__init__]


_TYPE_WORDS = {"float": "a number", "int": "an integer", "bool": "true or false",
               "str": "a string"}


def _check_params(path: Path, table: str, params: Mapping[str, Any],
                  targets: list[Callable[..., Any]]) -> dict[str, Any]:
    """``params`` of a ``[detector]`` / ``[templates]`` table, each value checked against the
    annotation of the constructor parameter it sets, ``"none"`` read as None where the
    parameter takes None (unknown keys are left to the constructor, whose message names
    them)."""
    types = _signature_types(targets)
    out = dict(params)
    for key, value in params.items():
        kinds = [k.strip() for k in types.get(key, "").split("|")]
        if "None" in kinds and isinstance(value, str) and value.lower() == "none":
            out[key] = None
            continue
        wanted = [k for k in kinds if k in _TYPE_WORDS]
        if not wanted or len(wanted) < len([k for k in kinds if k != "None"]):
            continue  # a type this check does not know
        ok = ((isinstance(value, bool) and "bool" in wanted)
              or (not isinstance(value, bool) and (
                  (isinstance(value, int) and ("int" in wanted or "float" in wanted))
                  or (isinstance(value, float) and "float" in wanted and math.isfinite(value))
                  or (isinstance(value, str) and "str" in wanted))))
        if not ok:
            words = " or ".join(_TYPE_WORDS[k] for k in wanted)
            if "None" in kinds:
                words += ' or "none"'
            raise InputError(f"{path}: {table}.{key} must be {words}, got {value!r}")
    return out


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
        if key not in TABLES:
            raise InputError(f"{path}: unknown table [{key}] (known: "
                             f"{', '.join(sorted(TABLES))})")
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
    if "gate" in tracker and not (isinstance(tracker["gate"], str)
                                  and tracker["gate"].lower() == "none"):
        _check_type(path, "tracker.gate", tracker["gate"], (int, float))
    check_tracker(tracker, lambda key: f"{path}: tracker.{key}", f"{path}: [tracker]")

    detector_table = dict(data.get("detector", {}))
    name = detector_table.pop("name", RunSettings.detector)
    _check_type(path, "detector.name", name, str)
    if name not in DETECTORS:
        raise InputError(
            f"{path}: detector.name {name!r} is not a detector (choose one of: "
            f"{', '.join(DETECTORS)})"
        )

    detector_table = _check_params(path, "detector", detector_table, detector_signatures(name))

    template_table = dict(data.get("templates", {}))
    enabled = template_table.pop("enabled", True)
    _check_type(path, "templates.enabled", enabled, bool)
    template_table = _check_params(path, "templates", template_table, template_signatures())

    video_table = data.get("video", {})
    for key in video_table:
        if key not in TABLES["video"]:
            raise _unknown(path, f"video.{key}", TABLES["video"])
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
