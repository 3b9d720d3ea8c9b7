"""Building the parts of a video run (detector, tracker, stopped-vehicle rescuer) from
:class:`~mvtrack.config.RunSettings`, with one-line errors for bad settings."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.config import RunSettings
from mvtrack.errors import InputError
from mvtrack.types import Detections
from mvtrack.video.loop import Rescuer
from mvtrack.video.rescue import StoppedVehicleRescuer, TemplateRescuer

Image = NDArray[np.uint8]


def build_detector(settings: RunSettings) -> Callable[[Image], Detections]:
    """The detection front end named in ``settings`` with its parameters.

    Raises
    ------
    ValueError
        Unknown front end or parameter (one line, from :func:`mvtrack.detection.make_detector`).
    """
    from mvtrack.detection import make_detector

    return make_detector(settings.detector, **settings.detector_params)


def build_tracker_config(settings: RunSettings, fps: float) -> Any:
    """The :class:`~mvtrack.tracking.TrackerConfig` of ``settings`` at frame rate ``fps``.

    ``settings.tracker["preset"]`` (default ``"default"``) is built for ``fps``; keys the preset
    function takes as arguments (e.g. ``paper1(predictor=...)``, which then picks the
    predictor's own parameters) are passed to it, the others replace fields of the result.
    Changing the distance to another one without a gate resets the gate to the new distance's
    default (a gate is in the distance's units: px² for ``euclidean``, χ² for the others);
    naming the preset's own distance changes nothing (:func:`mvtrack.tracking.preset`).
    TOML has no null, so the string ``"none"`` (any case) stands for ``None`` (e.g.
    ``birth_iou = "none"`` lets every detection left over start a track). ``frame_size``
    (the image's, :func:`~mvtrack.video.resolve_settings`) is the tracker's, not the
    configuration's (:func:`build_tracker`). A ``fps`` in ``settings.tracker``
    (``[tracker] fps`` of a settings file) wins over ``fps``: ``mvtrack track`` gives the
    source the same frame rate (:meth:`mvtrack.config.RunSettings.frame_rate`).

    Raises
    ------
    InputError
        Unknown preset or field, or a bad value (one line).
    """
    from mvtrack.tracking import PRESETS, TrackerConfig, preset

    params = {k: None if isinstance(v, str) and v.lower() == "none" else v
              for k, v in settings.tracker.items()}
    name = params.pop("preset", "default")
    params.pop("frame_size", None)
    # [tracker] fps (or --fps, which the command line puts there) is the run's frame rate:
    # it replaces the source's, and is given to the preset once
    fps = params.pop("fps", fps)
    if name not in PRESETS:
        raise InputError(f"unknown tracker preset {name!r}; choose one of: {', '.join(PRESETS)}")
    known = {f.name for f in dataclasses.fields(TrackerConfig)}
    for key in params:
        if key not in known:
            raise InputError(
                f"unknown tracker setting {key!r} (known: {', '.join(sorted(known))})"
            )
    try:
        return preset(name, fps=fps, **params)  # the one place presets are built
    except (TypeError, ValueError) as exc:
        raise InputError(f"tracker settings: {exc}") from None


def build_tracker(settings: RunSettings, fps: float) -> Any:
    """A fresh :class:`~mvtrack.tracking.Tracker` for ``settings`` (validates predictor etc.);
    an offline run's (``settings.offline``) outputs its tentative rows too, which the video
    loop keeps aside (:class:`mvtrack.video.offline.OfflineRows`)."""
    from mvtrack.tracking import Tracker

    config = build_tracker_config(settings, fps)
    if settings.offline:
        config = config.replace(output_tentative=True)
    size = settings.tracker.get("frame_size")
    try:
        return Tracker(config, frame_size=None if size is None else tuple(size))
    except (TypeError, ValueError) as exc:
        raise InputError(f"tracker settings: {exc}") from None


def build_rescuer(settings: RunSettings, tracker: Any, detector: Any = None) -> Rescuer:
    """Template matching for stopped vehicles (paper 1 §1.1 step 3) attached to ``tracker``.

    A :class:`~mvtrack.detection.template.TemplateBank` with ``settings.template_params``
    (NCC ≥ 0.8 inside the gate radius, SPEC §1.1 [R]; the bank owns the check that a track
    has driven somewhere before it is searched: ``min_travel`` box lengths, ``min_travel_px``,
    ``min_hits``) in its :class:`~mvtrack.video.rescue.TemplateRescuer`, given the
    ``detector`` (its foreground mask restricts the templates to the objects' own pixels),
    guarded by :class:`StoppedVehicleRescuer` (``max_shift``; ``pieces``: a vehicle that
    stands held by its template also while it stays foreground, the default).

    With a detector and no ``min_pixels`` in the settings, a template needs half the
    detector's ``min_area`` in object pixels (20 px at 320×240, 115 px at 768×576 with the
    size-dependent defaults): the bank's fixed 50 px dropped the templates of two-tone vehicles
    whose blob covers only one tone (two of the ten waiting vehicles of five ``intersection``
    runs lost their track).
    """
    from mvtrack.detection.template import TemplateBank

    params = dict(settings.template_params)
    min_area = getattr(getattr(detector, "blobs", None), "min_area", None)
    if min_area and "min_pixels" not in params:
        params["min_pixels"] = max(round(0.5 * min_area), 1)
    max_shift = params.pop("max_shift", StoppedVehicleRescuer.MAX_SHIFT)
    pieces = params.pop("pieces", True)
    try:
        bank = TemplateBank(**params)
        guard = StoppedVehicleRescuer(None, tracker, max_shift, pieces)
    except TypeError as exc:
        raise InputError(f"template settings: {exc}") from None
    # the guard searches around where each vehicle was last seen, not around the
    # prediction, and refuses matches farther than max_shift from there: the NCC looks that
    # far and no farther (the tracker's gate, a region about the prediction, is not read)
    guard.inner = TemplateRescuer(bank, tracker, gate_radius=guard.max_shift, detector=detector)
    return guard


def check_settings(settings: RunSettings, fps: float = 30.0) -> None:
    """Build the detector, the tracker and (with templates) the template bank of ``settings``
    once at the papers' image size, so bad settings fail before any frame is read or any
    worker starts.

    Raises
    ------
    ValueError
        Unknown preset, predictor, distance, assignment rule, detector or parameter.
    """
    from mvtrack.video.settings import REFERENCE_SIZE, resolve_settings

    resolved = resolve_settings(settings, REFERENCE_SIZE)
    build_detector(resolved)
    tracker = build_tracker(resolved, fps)
    if resolved.templates:
        build_rescuer(resolved, tracker)
