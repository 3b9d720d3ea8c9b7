"""The video package: frame loop, early ends (Ctrl-C, a failing source) and whole runs."""

from __future__ import annotations

import json
from collections.abc import Iterator

import numpy as np
import pytest

from _media import squares_video
from mvtrack.config import RunSettings
from mvtrack.types import Detections, TrackFrame
from mvtrack.video import run_frames, track_to_folder

DM = "disturbance-map"


class CountingTracker:
    """A stand-in tracker: every detection is its own track (ids 1..M), for loop tests."""

    def __init__(self) -> None:
        self.calls: list[tuple[int, int, bool]] = []

    def step(self, dets: Detections, rescue=None) -> TrackFrame:
        self.calls.append((dets.frame, len(dets), rescue is not None))
        m = len(dets)
        ids = np.arange(1, m + 1, dtype=np.int64)
        return TrackFrame(dets.frame, ids, np.ones(m, np.int64), np.arange(m), dets.xy,
                          dets.xy, dets.xy, dets.wh, np.zeros((m, 2)))


def one_blob_detector(frame: np.ndarray) -> Detections:
    """One detection at the brightest pixel (the frame index is set by the pipeline)."""
    y, x = np.unravel_index(int(frame[..., 0].argmax()), frame.shape[:2])
    return Detections(-1, [[float(x), float(y)]], [[4.0, 4.0]])


def _frames(n: int, fail_at: int | None = None, exc: BaseException | None = None):
    for k in range(n):
        if fail_at is not None and k == fail_at:
            raise exc  # type: ignore[misc]
        img = np.zeros((20, 30, 3), np.uint8)
        img[5, k % 30, 0] = 255
        yield img


def test_run_frames_numbers_frames_and_counts_detections() -> None:
    tracker = CountingTracker()
    res = run_frames(_frames(7), one_blob_detector, tracker, progress=False)
    assert res.n_frames == 7 and res.n_detections == 7 and not res.ended_early
    assert [c[0] for c in tracker.calls] == list(range(7))
    assert [t.frame for t in res.tracks] == list(range(7))
    np.testing.assert_allclose([t.measured_xy[0, 0] for t in res.tracks], np.arange(7))


def test_ctrl_c_mid_way_keeps_the_frames_so_far() -> None:
    res = run_frames(_frames(20, fail_at=5, exc=KeyboardInterrupt()), one_blob_detector,
                     CountingTracker(), progress=False)
    assert res.interrupted and res.ended_early and res.error is None
    assert res.n_frames == 5 and len(res.tracks) == 5


def test_ctrl_c_inside_the_tracker_is_also_clean() -> None:
    class Boom(CountingTracker):
        def step(self, dets, rescue=None):
            if dets.frame == 3:
                raise KeyboardInterrupt
            return super().step(dets, rescue)

    res = run_frames(_frames(10), one_blob_detector, Boom(), progress=False)
    assert res.interrupted and res.n_frames == 3


class SignallingTracker(CountingTracker):
    """Sends ``sig`` to its own process in the middle of the step of frame 3, then goes on
    with the step (as a compiled kernel would: Python code runs after the signal arrived)."""

    def __init__(self, sig: int) -> None:
        super().__init__()
        self.sig = sig
        self.finished: list[int] = []
        self.handlers: list[object] = []

    def step(self, dets: Detections, rescue=None) -> TrackFrame:
        import signal

        if dets.frame == 3:
            signal.raise_signal(self.sig)
            self.handlers.append(signal.getsignal(signal.SIGTERM))
        out = super().step(dets, rescue)
        self.finished.append(dets.frame)
        return out


@pytest.mark.parametrize("name", ["SIGINT", "SIGTERM"])
def test_a_signal_during_a_frame_ends_the_run_after_that_frame(name: str) -> None:
    """Ctrl-C or the command line's SIGTERM in the middle of the tracker's step: the step
    finishes (an exception raised inside the compiled kernels would come out of them as a
    SystemError), the frame is kept, the run ends there, and the handler that was installed
    is the one that decides (SIGTERM: the command line's, which says it was terminated)."""
    import signal

    from mvtrack.cli import _signals

    tracker = SignallingTracker(getattr(signal, name))
    before = (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM))
    with _signals.sigterm_as_interrupt():
        res = run_frames(_frames(10), one_blob_detector, tracker, progress=False)
        assert _signals.terminated() == (name == "SIGTERM")
    assert res.interrupted and res.n_frames == 4 and len(res.tracks) == 4
    assert tracker.finished == [0, 1, 2, 3]
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before


def test_a_signal_without_a_python_handler_is_left_alone() -> None:
    """An ignored SIGTERM stays ignored during the loop (so does the default one, which ends
    the process): only signals with a Python handler wait for the end of the frame."""
    import signal

    tracker = SignallingTracker(signal.SIGTERM)
    old = signal.signal(signal.SIGTERM, signal.SIG_IGN)
    try:
        res = run_frames(_frames(6), one_blob_detector, tracker, progress=False)
    finally:
        signal.signal(signal.SIGTERM, old)
    assert not res.interrupted and res.n_frames == 6
    assert tracker.handlers == [signal.SIG_IGN]


def test_source_failing_mid_way_is_reported_not_raised() -> None:
    res = run_frames(_frames(10, fail_at=4, exc=OSError("stream dropped")), one_blob_detector,
                     CountingTracker(), progress=False)
    assert res.error == "stream dropped" and res.ended_early and not res.interrupted
    assert res.n_frames == 4
    with pytest.raises(OSError, match="dropped"):
        run_frames(_frames(10, fail_at=0, exc=OSError("dropped")), one_blob_detector,
                   CountingTracker(), progress=False)


def test_max_frames_and_rescuer_are_honoured() -> None:
    seen: list[tuple[str, int]] = []

    class Rescuer:
        def callback(self, image, dets):
            assert dets.frame == int(image[5].argmax() // 3)
            seen.append(("callback", int(image[5].argmax() // 3)))
            return lambda uids, xy, wh: (np.zeros(len(uids), bool), xy)

        def observe(self, image, dets, tracks):
            seen.append(("observe", dets.frame))

    tracker = CountingTracker()
    res = run_frames(_frames(50), one_blob_detector, tracker, rescuer=Rescuer(), max_frames=4,
                     progress=False)
    assert res.n_frames == 4 and not res.ended_early
    assert all(c[2] for c in tracker.calls)
    assert seen == [("callback", 0), ("observe", 0), ("callback", 1), ("observe", 1),
                    ("callback", 2), ("observe", 2), ("callback", 3), ("observe", 3)]
    with pytest.raises(ValueError, match="max_frames"):
        run_frames(_frames(3), one_blob_detector, tracker, max_frames=0)


# ------------------------------------------------------------------ whole runs, real parts


def _settings(**kw) -> RunSettings:
    """The disturbance map's pipeline (the squares below are its test scenes)."""
    tracker = {"preset": "default"}
    kw.setdefault("detector", "disturbance-map")
    return RunSettings(tracker=tracker, templates=False, **kw)


def _match(log, centres: np.ndarray) -> dict[int, np.ndarray]:
    """For each true box j, the track id nearest to it (≤ 6 px) per frame, −1 if none."""
    out = {j: np.full(centres.shape[0], -1) for j in range(centres.shape[1])}
    for tf in log:
        for j in range(centres.shape[1]):
            if len(tf) == 0:
                continue
            d = np.hypot(*(tf.filtered_xy - centres[tf.frame, j]).T)
            i = int(d.argmin())
            if d[i] <= 6.0:
                out[j][tf.frame] = int(tf.track_id[i])
    return out


def test_rendered_boxes_give_one_track_each(tmp_path) -> None:
    frames, centres = squares_video(70)
    run = track_to_folder(frames, fps=30.0, size=(160, 120), settings=_settings(),
                          out=tmp_path, progress=False, source="squares")
    per_box = _match(run.log, centres)
    for j, ids in per_box.items():
        held = ids[20:]  # both boxes fully inside and confirmed
        assert (held > 0).mean() > 0.95, (j, ids)
        values, counts = np.unique(held[held > 0], return_counts=True)
        assert len(values) == 1, (j, values, counts)  # one identity over the whole run
    assert per_box[0][40] != per_box[1][40]
    assert run.summary["tracks"] >= 2 and run.summary["frames"] == 70
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["results.txt", "summary.json", "tracks.mp4", "trajectories.png"]


def test_output_files_are_complete(tmp_path) -> None:
    import cv2

    from mvtrack.io.mot import read_mot

    frames, _ = squares_video(40)
    run = track_to_folder(frames, fps=30.0, size=(160, 120), settings=_settings(),
                          out=tmp_path, progress=False)
    table = read_mot(tmp_path / "results.txt", "results")
    assert len(table) == run.log.to_mot(include_coasting=False).shape[0] > 0
    assert table.frame.max() <= 39
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["frames"] == 40 and summary["ended_early"] is False
    assert summary["tracks"] == len(np.unique(table.id))
    assert set(summary["states"]) >= {"confirmed", "coasting", "stopped"}
    assert summary["settings"]["detector"] == "disturbance-map"
    cap = cv2.VideoCapture(str(tmp_path / "tracks.mp4"))
    n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    ok, first = cap.read()
    cap.release()
    assert ok and first.shape == (120, 160, 3) and n == 40
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_ctrl_c_still_writes_results_of_the_frames_so_far(tmp_path) -> None:
    from mvtrack.io.mot import read_mot

    frames, _ = squares_video(60)

    def interrupted() -> Iterator[np.ndarray]:
        for k, f in enumerate(frames):
            if k == 30:
                raise KeyboardInterrupt
            yield f

    run = track_to_folder(interrupted(), fps=30.0, size=(160, 120), settings=_settings(),
                          out=tmp_path, progress=False)
    assert run.result.interrupted and run.summary["ended_early"] is True
    assert run.summary["frames"] == 30
    table = read_mot(tmp_path / "results.txt", "results")
    assert len(table) > 0 and table.frame.max() == 29
    assert (tmp_path / "tracks.mp4").stat().st_size > 0
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_no_video_skips_the_mp4(tmp_path) -> None:
    frames, _ = squares_video(20)
    track_to_folder(frames, fps=30.0, size=(160, 120), settings=_settings(video=False),
                    out=tmp_path, progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "results.txt", "summary.json", "trajectories.png"
    ]


# ------------------------------------------------------------------ the drawn gate is the gate


def _gate_probe(config, offset_dir: np.ndarray, factor: float, wh=(10.0, 8.0)) -> bool:
    """Track one ``wh`` box moving 2 px/frame for 12 frames, then put the next detection at
    ``factor`` times the drawn gate's extent along ``offset_dir``; True if it is associated."""
    from mvtrack.tracking import Tracker
    from mvtrack.viz.annotate import gate_ellipses

    tracker = Tracker(config)
    rng = np.random.default_rng(0)
    for k in range(12):
        xy = np.array([[40.0 + 2.0 * k, 60.0]]) + rng.normal(0, 0.3, (1, 2))
        tracker.step(Detections(k, xy, [wh]))
    gates = tracker.gates()
    assert len(gates) == 1 and gates.track_id[0] > 0
    center, shape, r2 = gates.center, gates.shape, gates.r2
    # distance to the boundary along offset_dir: t with (t u)ᵀ C⁻¹ (t u) = r²
    u = offset_dir / np.linalg.norm(offset_dir)
    t = np.sqrt(r2 / (u @ np.linalg.inv(shape[0]) @ u))
    axes, _ = gate_ellipses(shape, r2)
    assert axes[0, 1] - 1e-9 <= t <= axes[0, 0] + 1e-9
    out = tracker.step(Detections(12, center + factor * t * u, [wh]))
    return bool(len(out) and out.det_index[out.track_id == gates.track_id[0]][0] >= 0)


@pytest.mark.parametrize("preset", ["paper1", "paper2", "default", "uncoupled"])
@pytest.mark.parametrize("direction", [(1.0, 0.0), (0.0, 1.0), (1.0, -1.0)])
@pytest.mark.parametrize("wh", [(10.0, 8.0), (150.0, 40.0)])
def test_drawn_gate_is_the_trackers_gate(
    preset: str, direction: tuple[float, float], wh: tuple[float, float]
) -> None:
    """The region :meth:`Tracker.gates` gives to draw is the one the next step applies: a
    detection just inside its boundary is taken, one just outside is not, along any direction,
    for a small and a large box (the default's gate, the filter's innovation covariance in
    box sizes, grows with the box), for the
    papers' circle and coupled region, the default (the fused compiled step) and the
    uncoupled gate (the step composed from Python)."""
    from mvtrack.tracking import TrackerConfig
    from mvtrack.tracking import preset as make_preset

    if preset == "uncoupled":  # eq. (9) of paper 2 on the default's filter
        config = TrackerConfig(fps=30.0, distance="uncoupled")
    else:
        config = make_preset(preset, fps=30.0)
    d = np.asarray(direction)
    assert _gate_probe(config, d, 0.97, wh)
    assert not _gate_probe(config, d, 1.03, wh)


def test_a_large_box_is_drawn_with_a_gate_as_wide_as_the_box() -> None:
    """The default's gate is in box sizes: a 150×40 box's gate is about 150/40 times wider
    than high; the drawn outline crosses the row of its centre where the tracker's gate ends,
    and the tracker takes a detection there, far beyond the gate's height."""
    from mvtrack.tracking import Tracker, TrackerConfig
    from mvtrack.viz.annotate import annotate_frame, gate_ellipses

    tracker = Tracker(TrackerConfig())
    for k in range(8):
        tracker.step(Detections(k, [[100.0 + 2.0 * k, 60.0]], [[150.0, 40.0]]))
    g = tracker.gates()
    (a, b), angle = gate_ellipses(g.shape, g.r2)[0][0], gate_ellipses(g.shape, g.r2)[1][0]
    assert abs(angle) < 1.0 and 3.0 < a / b < 4.5  # along x, about w / h = 3.75
    c = g.center[0]
    frame = np.zeros((120, 320, 3), np.uint8)
    img = annotate_frame(frame, TrackFrame.empty(8), gate_center=g.center,
                         gate_cov=g.shape, gate_r2=g.r2)
    row = img[round(c[1]), :, :].any(axis=1)
    right = np.flatnonzero(row[round(c[0]):])
    assert right.size and abs(right.max() - a) <= 2.0  # anti-aliased outline
    # the tracker takes a detection at 0.9 a to the right (3 gate heights away) ...
    assert 0.9 * a > 3 * b
    taken = tracker.step(Detections(8, c[None] + [[0.9 * a, 0.0]], [[150.0, 40.0]]))
    assert taken.det_index.tolist() == [0]
    # ... and not one as far below its centre
    tracker2 = Tracker(TrackerConfig())
    for k in range(8):
        tracker2.step(Detections(k, [[100.0 + 2.0 * k, 60.0]], [[150.0, 40.0]]))
    below = tracker2.step(Detections(8, c[None] + [[0.0, 0.9 * a]], [[150.0, 40.0]]))
    assert (below.det_index[below.track_id > 0] < 0).all()


def test_the_video_sets_the_image_size_and_leaves_the_tracker_alone() -> None:
    """One tracker for every video: the image size reaches the tracker as its frame (a track
    that leaves it ends), nothing else of the tracker changes with the image; the front end's
    blob stage follows the image."""
    from mvtrack.tracking import TrackerConfig
    from mvtrack.video import build_tracker, build_tracker_config, resolve_settings

    small = resolve_settings(RunSettings(detector=DM), (320, 240))
    assert small.detector_params == {"min_area": 40.0, "close_size": 7, "ghost_every": 5,
                                     "hold": 1800,  # 60 s at the default 30 fps
                                     "track_split": True, "track_merge": False}
    mine_split = resolve_settings(
        RunSettings(detector=DM, detector_params={"track_split": True}), (320, 240))
    assert "track_merge" not in mine_split.detector_params  # the user's split merges too
    slow = resolve_settings(RunSettings(detector=DM), (320, 240), fps=10.0)
    assert slow.detector_params["hold"] == 600
    other = resolve_settings(RunSettings(detector="mog2"), (320, 240))
    assert other.detector_params == {"min_area": 40.0, "close_size": 7}
    assert small.tracker == {"frame_size": [320.0, 240.0]}
    big = resolve_settings(RunSettings(detector=DM), (640, 480))  # s² = 4
    assert big.detector_params["min_area"] == 160.0 and big.detector_params["close_size"] == 7
    assert big.tracker == {"frame_size": [640.0, 480.0]}
    for s, size in ((small, (320.0, 240.0)), (big, (640.0, 480.0))):
        assert build_tracker_config(s, 30.0) == TrackerConfig(fps=30.0)
        assert build_tracker(s, 30.0).frame_size == size
        assert build_tracker(s, 30.0).fused  # mvtrack track runs the compiled step
    default = resolve_settings(RunSettings(), (768, 576), fps=10.0)  # road-users, vtest.avi
    assert build_tracker(default, 10.0).fused
    mine = resolve_settings(
        RunSettings(tracker={"gate": 50.0, "measurement_noise": 0.2}, detector=DM,
                    detector_params={"min_area": 5.0}), (640, 480))
    assert mine.tracker == {"gate": 50.0, "measurement_noise": 0.2,
                            "frame_size": [640.0, 480.0]}
    assert build_tracker_config(mine, 30.0) == TrackerConfig(gate=50.0, measurement_noise=0.2)
    assert mine.detector_params["min_area"] == 5.0
    tiny = resolve_settings(RunSettings(detector=DM), (96, 64))
    assert tiny.tracker == {"frame_size": [96.0, 64.0]}
    assert tiny.detector_params["min_area"] == 3.0
    paper = resolve_settings(RunSettings(tracker={"preset": "paper1"}), (640, 480))
    assert paper.tracker == {"preset": "paper1", "frame_size": [640.0, 480.0]}
    # the scene front end sizes its own blob stage (working pixels, closing from its prior)
    scene = resolve_settings(RunSettings(detector="scene"), (640, 480))
    assert scene.detector_params == {} and scene.tracker == big.tracker
    # the road-user front end: the smallest blob follows the image (ROAD_USERS_AREA s²,
    # in its working pixels), its closing from the objects it learns; the user's value kept
    road = resolve_settings(RunSettings(detector="road-users"), (640, 480), fps=10.0)
    assert road.detector_params == {"min_area": 160.0, "absorb_after": 600,
                                    "ghost_every": 20}
    assert resolve_settings(RunSettings(detector="road-users"), (1224, 370)
                            ).detector_params["min_area"] == 236.0  # KITTI-17: s² = 5.90
    half = resolve_settings(RunSettings(detector="road-users", detector_params={"scale": 0.5}),
                            (640, 480))
    assert half.detector_params["min_area"] == 40.0  # 160 frame pixels at half scale
    own = resolve_settings(
        RunSettings(detector="road-users", detector_params={"min_area": 12.0}), (640, 480))
    assert own.detector_params["min_area"] == 12.0


def test_progress_bar_goes_to_stderr_only_when_asked(capsys) -> None:
    run_frames(_frames(5), one_blob_detector, CountingTracker(), progress=True, total=5)
    captured = capsys.readouterr()
    assert "tracking:" in captured.err and "/5" in captured.err and captured.out == ""
    run_frames(_frames(5), one_blob_detector, CountingTracker(), total=5)  # not a terminal
    assert capsys.readouterr().err == ""


def _stop_video(n: int = 200, seed: int = 1) -> list[np.ndarray]:
    """Box A (textured, two-tone) drives right at 2 px/frame from frame 10 and stops at frame
    40; box B appears at frame 20 and never moves. Textured grey road, noise σ = 2."""
    rng = np.random.default_rng(seed)
    h, w = 120, 200
    road = (90 + 8 * rng.standard_normal((h, w))).clip(0, 255)
    car = np.zeros((10, 16))
    car[:, :8], car[:, 8:] = 200, 150
    car[3:7, 2:14] = 40  # windows: texture for the template
    frames = []
    for k in range(n):
        img = road.copy()
        if k >= 10:
            x = 20 + 2 * (min(k, 40) - 10)
            img[40:50, x : x + 16] = car
        if k >= 20:
            img[85:95, 150:166] = car[:, ::-1]
        img = img + rng.normal(0, 2.0, img.shape)
        frames.append(np.repeat(img.clip(0, 255).astype(np.uint8)[..., None], 3, axis=2))
    return frames


def _ids_near(log, xy: tuple[float, float], frames: range) -> dict[int, tuple[int, int]]:
    """Per frame in ``frames``: (track id, state) of the row within 8 px of ``xy``."""
    out = {}
    for tf in log:
        if tf.frame in frames and len(tf):
            d = np.hypot(*(tf.filtered_xy - np.asarray(xy)).T)
            i = int(d.argmin())
            if d[i] <= 8.0:
                out[tf.frame] = (int(tf.track_id[i]), int(tf.state[i]))
    return out


def test_a_stopped_vehicle_keeps_its_id_by_template_matching(tmp_path) -> None:
    from mvtrack.types import TrackState

    frames = _stop_video()
    a_xy, b_xy = (87.5, 44.5), (157.5, 89.5)  # where A stands from frame 40, where B stands
    paper = {"hold": 0}  # paper 1's running average everywhere: A fades while it stands
    with_t = track_to_folder(frames, fps=30.0, size=(200, 120), out=tmp_path / "t",
                             settings=RunSettings(video=False, detector=DM,
                                                  detector_params=paper), progress=False)
    late = range(150, 200)  # long after A's blob has faded into the background
    held = _ids_near(with_t.log, a_xy, late)
    assert len(held) == len(late), "A is lost once it stops"
    ids = {i for i, _ in held.values()}
    assert len(ids) == 1
    assert all(s == int(TrackState.STOPPED) for _, s in held.values())
    # ... and it is the ID A had while driving
    moving = _ids_near(with_t.log, (60.0, 44.5), range(25, 27))
    assert moving and {i for i, _ in moving.values()} == ids
    # B never moved: nothing is held there once it has faded
    assert not _ids_near(with_t.log, b_xy, late)
    # without template matching A is lost too
    without = track_to_folder(frames, fps=30.0, size=(200, 120), out=tmp_path / "n",
                              settings=RunSettings(video=False, templates=False, detector=DM,
                                                   detector_params=paper),
                              progress=False)
    assert not _ids_near(without.log, a_xy, late)
    # the pipeline's default holds the tracked pixels out of the background: A stays a blob
    # and keeps the same ID by detection; B, which appeared and stands, is an object of the
    # scene too and stays tracked (it would be absorbed after the 60 s slow path)
    held_run = track_to_folder(frames, fps=30.0, size=(200, 120), out=tmp_path / "h",
                               settings=RunSettings(video=False, templates=False, detector=DM),
                               progress=False)
    kept = _ids_near(held_run.log, a_xy, late)
    assert len(kept) == len(late)
    assert all(s == int(TrackState.CONFIRMED) for _, s in kept.values())
    assert {i for i, _ in kept.values()} == {
        i for i, _ in _ids_near(held_run.log, (60.0, 44.5), range(25, 27)).values()}
    assert len(_ids_near(held_run.log, b_xy, late)) == len(late)


def test_stopped_vehicle_guard_accepts_only_what_a_stopped_vehicle_looks_like() -> None:
    """The guard around the NCC search: found where last measured, and not covered by a
    detection — checked on a stand-in search that finds every track. (That a track has driven
    somewhere before it is searched is the template bank's check,
    tests/detection/test_template.py.) The scores of the accepted matches go to the rows the
    tracker held with them."""
    from types import SimpleNamespace

    from mvtrack.types import TrackState
    from mvtrack.video import StoppedVehicleRescuer

    class FindsAll:
        def __init__(self) -> None:
            self.offset = np.zeros((4, 2))
            self.centres = None

        def search(self, image):
            def search(uids, xy, wh):
                self.centres = np.array(xy)
                return np.ones(len(uids), bool), xy + self.offset[uids], 0.81 + 0.05 * uids

            return search

        def observe(self, image, dets, tracks):
            pass

    inner = FindsAll()
    last = np.array([[20.0, 0.0], [50.0, 1.0], [120.0, 0.0], [170.0, 0.0]])
    tracker = SimpleNamespace(tracks=_table(np.zeros(4, int), last))
    guard = StoppedVehicleRescuer(inner, tracker, max_shift=4.0)
    image = np.zeros((10, 10, 3), np.uint8)
    inner.offset[2] = (6.0, 0.0)  # track 2's match lies 6 px from where it was last seen
    covering = Detections(1, [last[3] + 2.0], [[10.0, 10.0]])  # a detection covers track 3's
    rescue = guard.callback(image, covering)
    predicted = last + 7.0  # the filters drifted on: the search is centred on the last place
    found, xy = rescue(np.arange(4), predicted, np.full((4, 2), 8.0))
    np.testing.assert_allclose(inner.centres, last)
    assert found.tolist() == [True, True, False, False]
    np.testing.assert_allclose(xy[:2], last[:2])
    assert np.isnan(xy[2:]).all()
    # the tracker's output: uids 1, 0 held (IDs 11, 10), uid 2 coasting, a new tentative row
    held, coast = int(TrackState.STOPPED), int(TrackState.COASTING)
    tracker.row_uids = np.array([1, 2, 0, 7])
    out = TrackFrame(1, np.array([11, 12, 10, -1]),
                     np.array([held, coast, held, int(TrackState.TENTATIVE)]),
                     np.array([-1, -1, -1, 0]), *(np.ones((4, 2)) for _ in range(5)))
    guard.observe(image, covering, out)
    assert guard.held_scores.track_id.tolist() == [11, 10]
    np.testing.assert_allclose(guard.held_scores.score, [0.86, 0.81])
    guard.callback(image, covering)  # a frame whose step offers it no track
    guard.observe(image, covering, out)
    assert guard.held_scores.track_id.size == 0
    with pytest.raises(ValueError, match="max_shift"):
        StoppedVehicleRescuer(inner, tracker, max_shift=0.0)


def test_could_stand_by_hand() -> None:
    """``|v_a| Δk ≤ s_a / 2`` on both axes, by hand; NaN velocity passes."""
    from mvtrack.video.stopped import could_stand

    v = np.array([[9.0, 0.0], [11.0, 0.0], [0.0, 6.0], [4.0, 1.0], [np.nan, np.nan]])
    frames = np.array([2, 1, 1, 3, 5])
    size = np.array([[40.0, 10.0], [20.0, 10.0], [40.0, 10.0], [40.0, 10.0], [4.0, 4.0]])
    # 18 ≤ 20; 11 > 10; 6 > 5; 12 ≤ 20 and 3 ≤ 5; no evidence
    assert could_stand(v, frames, size).tolist() == [True, False, False, True, True]


def test_a_vehicle_missed_while_it_drives_on_is_not_held_where_it_was_last_seen() -> None:
    """With a real tracker and a stand-in search that finds every vehicle where it was last
    measured (as the empty road matches the template of a car of the road's colour): the
    car that stood before it was missed is held (``STOPPED``); the one missed while driving
    50 px a frame at 3 fps, more than half its 80 px box, is not (it coasts, no row)."""
    from mvtrack.tracking import Tracker, TrackerConfig
    from mvtrack.types import TrackState
    from mvtrack.video import StoppedVehicleRescuer

    class FindsAll:
        def search(self, image):
            return lambda uids, xy, wh: (np.ones(len(uids), bool), np.array(xy),
                                         np.full(len(uids), 0.9))

        def observe(self, image, dets, tracks):
            pass

    n = 12
    driving = np.column_stack([50.0 + 50.0 * np.arange(n), np.full(n, 100.0)])
    standing = np.column_stack([np.minimum(50.0 + 2.0 * np.arange(n), 60.0), np.full(n, 300.0)])
    tracker = Tracker(TrackerConfig(fps=3.0))
    guard = StoppedVehicleRescuer(FindsAll(), tracker, max_shift=4.0)
    image = np.zeros((10, 10, 3), np.uint8)
    for k in range(n - 1):
        dets = Detections(k, [driving[k], standing[k]], [[80.0, 40.0]] * 2)
        tracker.step(dets, rescue=guard.callback(image, dets))
    missed = Detections.empty(n - 1)
    out = tracker.step(missed, rescue=guard.callback(image, missed))
    state = dict(zip(np.round(out.filtered_xy[:, 1]).astype(int).tolist(),
                     out.state.tolist(), strict=True))
    assert state[300] == int(TrackState.STOPPED)
    assert state.get(100) != int(TrackState.STOPPED)  # no row: it coasts unseen


class _Bank:
    """A stand-in template bank: each track's template box (centre x, y, w, h)."""

    def __init__(self, boxes: np.ndarray) -> None:
        self._boxes = boxes

    def __len__(self) -> int:
        return len(self._boxes)

    def boxes(self, uids):
        return self._boxes[np.asarray(uids)]

    def rows(self):  # the bank as the compiled steps read it: uids 0..n-1, a sentinel last
        n = len(self._boxes)
        f = np.full((n + 1, 13), np.nan)
        f[:n, :4] = self._boxes
        return np.append(np.arange(n), np.iinfo(np.int64).max), f


class _Search:
    """A stand-in NCC search that finds every track ``offset`` px from where it is asked."""

    def __init__(self, bank: _Bank, n: int) -> None:
        self.bank = bank
        self.offset = np.zeros((n, 2))
        self.asked: list[np.ndarray] = []

    def search(self, image):
        def search(uids, xy, wh):
            self.asked.append(np.array(uids))
            return np.ones(len(uids), bool), xy + self.offset[uids], np.full(len(uids), 0.9)

        return search

    def observe(self, image, dets, tracks):
        pass


def _table(state, last, track_id=None):
    """A track table of uids 0..n-1 with their states, last measurements and IDs."""
    from mvtrack.tracking.lifecycle import LAST_X, LAST_Y, N_FLOAT, N_INT, STATE, TID, UID
    from mvtrack.tracking.table import TrackTable

    n = len(state)
    ints, floats = np.zeros((n, N_INT), np.int64), np.zeros((n, N_FLOAT))
    ints[:, UID], ints[:, STATE] = np.arange(n), state
    ints[:, TID] = np.arange(n) if track_id is None else track_id
    floats[:, LAST_X:LAST_Y + 1] = last
    return TrackTable(ints, floats)


def _guard(state, last, boxes, velocity, offset=None, pieces=True):
    from types import SimpleNamespace

    from mvtrack.video import StoppedVehicleRescuer

    n = len(boxes)
    inner = _Search(_Bank(np.array(boxes, float)), n)
    if offset is not None:
        inner.offset[:] = offset
    tracker = SimpleNamespace(
        tracks=_table(state, last, np.arange(n) + 10),
        row_uids=np.arange(n), config=SimpleNamespace(fps=10.0))
    guard = StoppedVehicleRescuer(inner, tracker, max_shift=4.0, pieces=pieces)
    # the last frame's rows: their velocities (px/frame) and boxes tell which tracks stand
    rows = TrackFrame(0, np.arange(n) + 10, np.array(state), np.full(n, -1),
                      *(np.zeros((n, 2)) for _ in range(3)), np.array(boxes, float)[:, 2:],
                      np.array(velocity, float))
    guard.observe(np.zeros((10, 10, 3), np.uint8), Detections.empty(0), rows)
    return guard, inner


def test_pieces_of_a_vehicle_that_stands_are_left_to_its_template() -> None:
    """A detection inside the template's box (widened by ``max_shift``) of a track that
    stands, was last measured there and whose template still matches there, belongs to
    that vehicle (a piece of it): left out of the tracker's step. Not when the track moves
    (a speed of a box side per second or more), was last measured elsewhere, or its match
    lies more than ``max_shift`` px away; nor a detection that reaches out of the box."""
    from mvtrack.types import TrackState

    ok = int(TrackState.CONFIRMED)
    boxes = [[50, 50, 20, 30], [150, 50, 20, 30], [250, 50, 20, 30], [350, 50, 20, 30],
             [450, 50, 20, 30]]
    last = [[50, 55], [150, 50], [250, 50], [350, 120], [450, 50]]
    # track 1 moves 2 px a frame (20 px/s at 10 fps, a side of 20 px per second): not still
    velocity = [[0.5, 0], [2.0, 0], [0, 0.3], [0, 0], [0, 0]]
    offset = np.zeros((5, 2))
    offset[2] = (0, 5.0)  # track 2's template matches 5 px from its place: it has moved on
    guard, inner = _guard([ok] * 5, last, boxes, velocity, offset)
    image = np.zeros((200, 500, 3), np.uint8)
    tlwh = np.array([
        [42, 45, 20, 16],   # 0: the rear half of vehicle 0, 2 px out of its box: a piece
        [52, 38, 10, 10],   # 1: inside vehicle 0's box
        [35, 40, 20, 20],   # 2: reaches 5 px out of it (a car passing by): kept
        [142, 50, 16, 14],  # 3: inside the box of track 1, which moves: kept
        [242, 50, 16, 14],  # 4: inside the box of track 2, matched too far: kept
        [342, 50, 16, 14],  # 5: inside the box of track 3, last measured far off: kept
        [441, 36, 18, 28],  # 6: track 4, whole (the vehicle itself): left to its template
    ], float)
    drop = guard.fragments(image, Detections.from_tlwh(0, tlwh))
    assert drop.tolist() == [True, True, False, False, False, False, True]
    # the search ran for the tracks that stand with a detection inside their box, at the
    # box's centre
    assert sorted(np.concatenate(inner.asked).tolist()) == [0, 2, 4]
    # the callback of the same frame takes the matches found, and searches only the others
    asked = len(inner.asked)
    found, xy = guard.callback(image, Detections.empty(0))(
        np.array([0, 3, 4]), np.zeros((3, 2)), np.full((3, 2), 20.0))
    assert found.tolist() == [True, True, True]
    np.testing.assert_allclose(xy, [[50, 50], [350, 120], [450, 50]])
    assert [a.tolist() for a in inner.asked[asked:]] == [[3]]
    # nothing to search: no detection, or no track stands
    assert not guard.fragments(image, Detections.empty(0)).size
    still, _ = _guard([ok] * 5, last, boxes, [[3.0, 0]] * 5)
    assert not still.fragments(image, Detections.from_tlwh(0, tlwh)).any()
    # paper 1's rule (the paper experiments): only tracks without a detection are searched
    paper, inner = _guard([ok] * 5, last, boxes, velocity, offset, pieces=False)
    assert not paper.fragments(image, Detections.from_tlwh(0, tlwh)).any() and not inner.asked


def test_template_settings_choose_paper_1s_rule() -> None:
    """``[templates] pieces = false`` (the paper experiments' setting) reaches the guard;
    the pipeline's default holds vehicles that stand in pieces."""
    from mvtrack.tracking import Tracker
    from mvtrack.video.build import build_rescuer

    assert build_rescuer(RunSettings(), Tracker()).pieces
    assert not build_rescuer(RunSettings(template_params={"pieces": False}), Tracker()).pieces


def test_a_vehicle_held_by_its_template_stays_held_under_a_blob_reaching_beyond_it() -> None:
    """A blob covering a vehicle's match refuses the match (a detected object has not
    faded), unless it is several times the vehicle's size, or the vehicle was held by its
    template in the last frame and the blob reaches out of its template's box (a car
    passing close by merged with its pieces). A blob inside the box still refuses it."""
    from mvtrack.types import TrackState

    held, ok = int(TrackState.STOPPED), int(TrackState.CONFIRMED)
    boxes = [[50, 50, 20, 30], [150, 50, 20, 30], [250, 50, 20, 30]]
    guard, _ = _guard([held, ok, held], [[50, 50], [150, 50], [250, 50]], boxes,
                      [[0, 0]] * 3)
    image = np.zeros((100, 300, 3), np.uint8)
    passing = np.array([[30, 40, 34, 24], [130, 40, 34, 24], [242, 40, 16, 24]], float)
    rescue = guard.callback(image, Detections.from_tlwh(0, passing))
    found, xy = rescue(np.arange(3), np.array(boxes, float)[:, :2], np.full((3, 2), 20.0))
    assert found.tolist() == [True, False, False]
    np.testing.assert_allclose(xy[0], [50, 50])
    assert np.isnan(xy[1:]).all()
    paper, _ = _guard([held, ok, held], [[50, 50], [150, 50], [250, 50]], boxes, [[0, 0]] * 3,
                      pieces=False)
    found, _ = paper.callback(image, Detections.from_tlwh(0, passing))(
        np.arange(3), np.array(boxes, float)[:, :2], np.full((3, 2), 20.0))
    assert not found.any()


def test_the_tracker_never_sees_the_dropped_detections_the_rest_does() -> None:
    """``step_without``: the rescuer's callback and the tracker get the detections not
    dropped; the rows' ``det_index`` point into the frame's detections as the front end
    gave them."""
    from mvtrack.video.loop import step_without

    seen = {}

    class Tracker:
        def step(self, dets, rescue=None):
            seen["step"] = dets.xy[:, 0].tolist()
            return TrackFrame(0, np.array([1, 2, 3]), np.ones(3, np.int64),
                              np.array([1, -1, 0]), *(np.zeros((3, 2)) for _ in range(5)))

    class Rescuer:
        def callback(self, image, dets):
            seen["callback"] = dets.xy[:, 0].tolist()

    dets = Detections(0, [[10.0, 0], [20.0, 0], [30.0, 0], [40.0, 0]], np.ones((4, 2)))
    out = step_without(Tracker(), Rescuer(), None, dets, np.array([True, False, True, False]))
    assert seen == {"step": [20.0, 40.0], "callback": [20.0, 40.0]}
    assert out.det_index.tolist() == [3, -1, 1]
    out = step_without(Tracker(), Rescuer(), None, dets, np.zeros(4, bool))
    assert seen["step"] == [10.0, 20.0, 30.0, 40.0] and out.det_index.tolist() == [1, -1, 0]
