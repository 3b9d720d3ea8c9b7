"""Traffic analytics on track logs: counts on lines, zones, turning movements, speeds.

Plain functions over arrays, with thin edges:

- :mod:`~mvtrack.analytics.tracks` — :class:`TrackPoints`, every track row as arrays (from a
  ``TrackLog`` or a MOTChallenge results file), and windows over each track's rows;
- :mod:`~mvtrack.analytics.lines` — directional count lines with hysteresis;
- :mod:`~mvtrack.analytics.zones` — zones: visits, dwell, occupancy;
- :mod:`~mvtrack.analytics.movements` — origin–destination of every track, completed from
  its heading when it ends mid-intersection;
- :mod:`~mvtrack.analytics.calibration` — image → ground homography and its Jacobian;
- :mod:`~mvtrack.analytics.speed` — ground speeds in km/h with their standard error;
- :mod:`~mvtrack.analytics.settings` — the ``[analytics]`` table of a TOML file;
- :mod:`~mvtrack.analytics.run` — :func:`analyse`: all of it, as tables per interval;
- :mod:`~mvtrack.analytics.outputs` — ``counts.csv``, ``movements.csv``, ``speeds.csv``,
  ``tracks.csv``;
- :mod:`~mvtrack.analytics.accuracy` — count errors and speed RMSE against ground truth;
- :mod:`~mvtrack.analytics.report` — the self-contained ``report.html`` of a run.

>>> from mvtrack.analytics import analyse_log, load_settings
"""

from mvtrack.analytics.calibration import GroundCalibration
from mvtrack.analytics.lines import CountLine, line_crossings
from mvtrack.analytics.movements import MovementSettings, track_movements
from mvtrack.analytics.run import AnalyticsResult, analyse, analyse_folder, analyse_log
from mvtrack.analytics.settings import AnalyticsSettings, load_settings, settings_from_dict
from mvtrack.analytics.speed import SpeedSettings, row_speeds, track_speeds
from mvtrack.analytics.tracks import TrackPoints
from mvtrack.analytics.zones import Zone, occupancy, zone_visits

__all__ = [
    "AnalyticsResult",
    "AnalyticsSettings",
    "CountLine",
    "GroundCalibration",
    "MovementSettings",
    "SpeedSettings",
    "TrackPoints",
    "Zone",
    "analyse",
    "analyse_folder",
    "analyse_log",
    "line_crossings",
    "load_settings",
    "occupancy",
    "row_speeds",
    "settings_from_dict",
    "track_movements",
    "track_speeds",
    "zone_visits",
]
