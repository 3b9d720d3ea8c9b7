"""Which analytics settings ``mvtrack analyze`` and ``mvtrack report`` use for a run's folder,
and the default ones for a scene nobody has described.

The settings, first found first:

1. the ``[analytics]`` table of ``--config FILE``;
2. the table of the folder's earlier analysis (``analytics.json``, written beside the CSV
   files), so that rerunning the command without ``--config`` redoes the same analysis and
   never replaces its counts with others;
3. the ``[analytics]`` table the run was tracked with (``summary.json`` of ``mvtrack track
   --config``).

A table that draws nothing to count on (no lines, zones or approaches) gets the default
geometry of :func:`border_table`, for any scene, from the image size in ``summary.json``:
every track's origin and destination at the image border (four approaches: the border band
split by the image diagonals into ``north``, ``east``, ``south`` and ``west``) and two count
lines through the middle of the image. Without an image size, and nothing given, the command
is refused with one line saying what to give.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mvtrack.analytics.settings import AnalyticsSettings, read_table, settings_from_dict
from mvtrack.errors import InputError

#: the record of an analysis, beside its CSV files
RECORD_NAME = "analytics.json"
#: depth of the border approaches, as a share of the image's shorter side
BORDER = 0.1
_GEOMETRY = ("lines", "zones", "approaches")


@dataclass(frozen=True)
class ChosenSettings:
    """The analytics settings of a folder, the table they were read from, and where from.

    Attributes
    ----------
    settings : AnalyticsSettings
    table : dict
        The ``[analytics]`` table (defaults filled in), as written to ``analytics.json``.
    source : str
        Where the settings come from, one line for the user.
    origin : str
        Where the table first came from (kept in ``analytics.json`` when it is reused).
    """

    settings: AnalyticsSettings
    table: dict[str, Any]
    source: str
    origin: str


def border_table(size: tuple[float, float]) -> dict[str, Any]:
    """The default geometry of a ``w × h`` image, as an ``[analytics]`` table.

    Approaches: the band of depth ``d = BORDER · min(w, h)`` along the border, split by the
    image diagonals (each corner's square goes half to either side), so every point of the
    band belongs to one side. Lines: ``vertical`` from ``(w/2, 0)`` to ``(w/2, h)``
    (``westbound`` is a crossing from its screen-left, x > w/2, to its right), and
    ``horizontal`` from ``(0, h/2)`` to ``(w, h/2)`` (``southbound`` from y < h/2 to
    y > h/2).
    """
    w, h = (float(v) for v in size)
    d = round(BORDER * min(w, h), 1)
    return {
        "approaches": {
            "north": {"polygon": [[0.0, 0.0], [w, 0.0], [w - d, d], [d, d]]},
            "east": {"polygon": [[w, 0.0], [w, h], [w - d, h - d], [w - d, d]]},
            "south": {"polygon": [[w, h], [0.0, h], [d, h - d], [w - d, h - d]]},
            "west": {"polygon": [[0.0, h], [0.0, 0.0], [d, d], [d, h - d]]},
        },
        "lines": {
            "vertical": {"points": [[w / 2, 0.0], [w / 2, h]],
                         "labels": ["westbound", "eastbound"]},
            "horizontal": {"points": [[0.0, h / 2], [w, h / 2]],
                           "labels": ["southbound", "northbound"]},
        },
    }


def _summary(folder: Path) -> dict[str, Any]:
    from mvtrack.analytics.run import folder_info

    return folder_info(folder)


def _record(folder: Path) -> tuple[dict[str, Any], str] | None:
    path = folder / RECORD_NAME
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise InputError(f"{path}: not a readable record of an analysis ({exc})") from None
    if not (isinstance(data, dict) and isinstance(data.get("analytics"), dict)):
        raise InputError(f"{path}: not a record of an analysis (no 'analytics' table)")
    return data["analytics"], str(data.get("source", "an earlier analysis"))


def choose_settings(folder: str | os.PathLike[str],
                    config: str | os.PathLike[str] | None = None) -> ChosenSettings:
    """The analytics settings for the run in ``folder`` (module docstring).

    Raises
    ------
    InputError
        A bad settings file or record (one line naming file and key); no geometry given and
        no image size to draw the default one.
    """
    folder = Path(folder)
    record = None
    if config is not None:
        table, where, source = read_table(config), config, f"the [analytics] table of {config}"
    elif (record := _record(folder)) is not None:
        table, where = record[0], folder / RECORD_NAME
        source = f"those of the earlier analysis ({RECORD_NAME}: {record[1]})"
    else:
        run = _summary(folder).get("settings", {})
        table = run.get("analytics") if isinstance(run, dict) else None
        where = folder / "summary.json"
        source = "the [analytics] table the run was tracked with (summary.json)"
        if not isinstance(table, dict):
            table, source = {}, "no --config, and none recorded in the folder"
    table = dict(table)
    if config is not None and not any(table.get(k) for k in _GEOMETRY):
        source = f"{config} draws no lines, zones or approaches"

    origin = record[1] if config is None and record is not None else source
    if not any(table.get(k) for k in _GEOMETRY):
        size = _summary(folder).get("size")
        if not (isinstance(size, list) and len(size) == 2
                and all(isinstance(v, (int, float)) and v > 0 for v in size)):
            raise InputError(
                f"{folder}: nothing to count on ({source}: no lines, zones or approaches) and "
                "no image size in summary.json for the default ones: give --config FILE with "
                "an [analytics] table (example: docs/analytics-example.toml)")
        table.update(border_table((size[0], size[1])))
        geometry = (f"; default geometry for the {size[0]}×{size[1]} image: approaches at "
                    "the four borders (north, east, south, west) and count lines through the "
                    "middle (vertical, horizontal)")
        source, origin = source + geometry, origin + geometry
    settings = settings_from_dict(table, where)
    if settings.calibration is None:
        source += "; no calibration, so no speeds"
    return ChosenSettings(settings, table, source, origin)


def write_record(chosen: ChosenSettings, folder: str | os.PathLike[str]) -> Path:
    """Write ``analytics.json`` (the table and where it came from) into ``folder``."""
    from mvtrack.io.atomic import write_json

    return write_json(Path(folder) / RECORD_NAME,
                      {"source": chosen.origin, "analytics": chosen.table})
