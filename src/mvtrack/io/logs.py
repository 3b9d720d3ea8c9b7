"""Keep OpenCV's and FFmpeg's own log lines off the terminal unless asked for.

mvtrack reports every problem with a video itself, in one line (``error: cannot read video
file x.mp4 ...``). Left alone, the libraries print their own lines first, such as
``[mov,mp4,m4a,3gp,3g2,mj2 @ 0x55…] moov atom not found`` from FFmpeg or ``[ WARN:0@0.05]
global cap_v4l.cpp … can't open camera by index`` from OpenCV. Importing :mod:`mvtrack.io`
calls :func:`quiet_backends`; ``mvtrack --verbose`` calls :func:`set_verbose`.

Both libraries read their settings from the environment: OpenCV's log level
(``OPENCV_LOG_LEVEL``) when ``cv2`` is imported, its FFmpeg back end's
(``OPENCV_FFMPEG_LOGLEVEL``, an FFmpeg ``AV_LOG_*`` level; -8 is ``AV_LOG_QUIET``) once, when
the process first opens a video through FFmpeg. A level the user has set is kept.
"""

from __future__ import annotations

import os
import sys

#: What "quiet" sets, where the user has set nothing.
QUIET: dict[str, str] = {"OPENCV_FFMPEG_LOGLEVEL": "-8", "OPENCV_LOG_LEVEL": "SILENT"}


def _users_own(key: str) -> bool:
    """Whether ``key`` holds a value of the user's, other than the quiet one."""
    value = os.environ.get(key)
    return value is not None and value != QUIET[key]


def _opencv_level(verbose: bool) -> None:
    """Set the level of an already imported ``cv2`` (the environment is read at its import)."""
    cv2 = sys.modules.get("cv2")
    logging = getattr(getattr(cv2, "utils", None), "logging", None)
    if logging is None or _users_own("OPENCV_LOG_LEVEL"):
        return
    logging.setLogLevel(logging.LOG_LEVEL_WARNING if verbose else logging.LOG_LEVEL_SILENT)


def quiet_backends() -> None:
    """Silence OpenCV and FFmpeg in this process (and the processes it starts)."""
    for key, value in QUIET.items():
        os.environ.setdefault(key, value)
    _opencv_level(verbose=False)


def set_verbose(verbose: bool = True) -> None:
    """Let OpenCV and FFmpeg print their own messages again (``verbose``), or silence them.

    FFmpeg's setting takes effect only before the process opens its first video (OpenCV reads
    it once); OpenCV's own takes effect at once. Call it first thing, as ``mvtrack --verbose``
    does. A level the user chose (other than the quiet one) is kept.
    """
    for key, value in QUIET.items():
        if _users_own(key):
            continue
        if verbose:
            os.environ.pop(key, None)  # the libraries' defaults: errors and warnings on stderr
        else:
            os.environ[key] = value
    _opencv_level(verbose)
