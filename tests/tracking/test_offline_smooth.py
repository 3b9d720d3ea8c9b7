"""Offline smoothing of each track (:mod:`mvtrack.tracking.smooth`): the Rauch–Tung–Striebel
smoother checked against filterpy's, and what it does to a walker's boxes."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from mvtrack.tracking import TrackerConfig, track_detections
from mvtrack.tracking import smooth as smooth_module
from mvtrack.tracking.config import MODE_TIMES
from mvtrack.tracking.smooth import smooth_tracks
from mvtrack.types import Detections, TrackFrame, TrackState


def _track_rows(rng: np.random.Generator, tid: int, frames: np.ndarray, measured: np.ndarray
                ) -> dict[int, tuple]:
    """Rows of one track: a tracker box growing slowly, noisy detection boxes and centres."""
    n = frames.size
    box = np.stack([np.linspace(30, 40, n), np.linspace(70, 90, n)], axis=1)
    det_box = box * np.exp(rng.normal(0, 0.1, (n, 2)))
    xy = np.stack([100 + 3 * frames, 200 - 1.5 * frames], axis=1) + rng.normal(0, 4, (n, 2))
    rows = {}
    for i, f in enumerate(frames):
        m = measured[i]
        rows[int(f)] = (tid, int(TrackState.CONFIRMED if m else TrackState.COASTING),
                        i if m else -1, xy[i] if m else np.full(2, np.nan), xy[i] + 1.0,
                        box[i], det_box[i] if m else np.full(2, np.nan))
    return rows


def _frames(tracks: list[dict[int, tuple]]) -> tuple[list[TrackFrame], list[np.ndarray]]:
    out, sizes = [], []
    for f in sorted({f for t in tracks for f in t}):
        rows = [t[f] for t in tracks if f in t]
        out.append(TrackFrame(
            f, np.array([r[0] for r in rows]), np.array([r[1] for r in rows]),
            np.array([r[2] for r in rows]), np.array([r[3] for r in rows]),
            np.array([r[4] for r in rows]), np.full((len(rows), 2), np.nan),
            np.array([r[5] for r in rows]), np.zeros((len(rows), 2))))
        sizes.append(np.array([r[6] for r in rows]))
    return out, sizes


def _filterpy_position(rows: dict[int, tuple], config: TrackerConfig) -> list[np.ndarray]:
    """filterpy's Kalman filter and RTS smoother on each axis of one track, the process
    noise of each step the two modes' ``Q`` weighted by their posterior probabilities, which
    are worked out here step by step with scalar formulas: the Markov switching over ``Δt``
    from the previous weights, times each mode's Gaussian likelihood of the innovation on
    both axes."""
    frames = sorted(rows)
    t = np.array(frames) / config.fps
    taus = np.array(MODE_TIMES)
    accel = [config.accel_noise, config.manoeuvre_noise]
    kfs, fs, qs = [], [[np.eye(2)], [np.eye(2)]], [[np.zeros((2, 2))], [np.zeros((2, 2))]]
    means, covs = [[], []], [[], []]
    for axis in (0, 1):
        kf = KalmanFilter(dim_x=2, dim_z=1)
        kf.x = np.array([rows[frames[0]][3][axis], 0.0])
        w0 = rows[frames[0]][5][axis]
        kf.P = np.diag([(config.measurement_noise * w0) ** 2, (config.velocity_prior * w0) ** 2])
        kf.H = np.array([[1.0, 0.0]])
        kfs.append(kf)
        means[axis].append(kf.x.copy())
        covs[axis].append(kf.P.copy())
    mu = taus / taus.sum()
    for k in range(1, len(frames)):
        dt = t[k] - t[k - 1]
        f = np.array([[1.0, dt], [0.0, 1.0]])
        stay = np.exp(-dt / taus)
        prior = np.array([mu[0] * stay[0] + mu[1] * (1 - stay[1]),
                          mu[1] * stay[1] + mu[0] * (1 - stay[0])])
        row = rows[frames[k]]
        measured = row[2] >= 0
        loglik = np.zeros(2)
        for axis in (0, 1):
            w = row[5][axis]
            pp = (f @ kfs[axis].P @ f.T)[0, 0]
            e = row[3][axis] - (f @ kfs[axis].x)[0] if measured else 0.0
            for i in (0, 1):
                s = pp + (accel[i] * w) ** 2 * dt**3 / 3 + (config.measurement_noise * w) ** 2
                loglik[i] += -0.5 * (e**2 / s + np.log(s)) if measured else 0.0
        post = prior * np.exp(loglik - loglik.max())
        mu = post / post.sum()
        for axis in (0, 1):
            w = row[5][axis]
            a2 = (mu[0] * accel[0] ** 2 + mu[1] * accel[1] ** 2) * w**2
            q = a2 * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
            kfs[axis].predict(F=f, Q=q)
            if measured:
                kfs[axis].update(row[3][axis], R=(config.measurement_noise * w) ** 2)
            fs[axis].append(f)
            qs[axis].append(q)
            means[axis].append(kfs[axis].x.copy())
            covs[axis].append(kfs[axis].P.copy())
    out = []
    for axis in (0, 1):
        xs, _, _, _ = kfs[axis].rts_smoother(np.array(means[axis]), np.array(covs[axis]),
                                             Fs=fs[axis], Qs=qs[axis])
        out.append(xs)
    return out


def _filterpy_size(rows: dict[int, tuple], axis: int, config: TrackerConfig) -> np.ndarray:
    """filterpy on ln(size) as a random walk (1-D state)."""
    frames = sorted(rows)
    t = np.array(frames) / config.fps
    z = [np.log(rows[f][6][axis]) if rows[f][2] >= 0 else None for f in frames]
    kf = KalmanFilter(dim_x=1, dim_z=1)
    kf.x = np.array([z[0]])
    kf.P = np.array([[config.measurement_noise**2]])
    kf.H = np.array([[1.0]])
    kf.R = np.array([[config.measurement_noise**2]])
    fs = [np.eye(1)] * len(frames)
    qs = [np.zeros((1, 1))] + [np.array([[smooth_module.SIZE_DRIFT**2 * (t[k] - t[k - 1])]])
                               for k in range(1, len(frames))]
    means, covs, _, _ = kf.batch_filter([None, *z[1:]], Fs=fs, Qs=qs)
    xs, _, _, _ = kf.rts_smoother(means, covs, Fs=fs, Qs=qs)
    return xs[:, 0]


@pytest.mark.parametrize("fps", [5.0, 30.0])
@pytest.mark.parametrize("manoeuvre", [15.0, 1.0])  # 1: the modes coincide, one plain RTS
def test_smoothed_rows_equal_filterpys_rts_smoother(fps: float, manoeuvre: float) -> None:
    rng = np.random.default_rng(3)
    config = TrackerConfig(fps=fps, manoeuvre_noise=manoeuvre)
    # three tracks of different lengths at once, with missed frames and a jump of 4 frames
    f1 = np.array([0, 1, 2, 3, 4, 8, 9, 10, 11, 12, 13, 14])
    m1 = np.array([1, 1, 1, 0, 1, 1, 1, 0, 0, 1, 1, 1], bool)
    f2 = np.arange(5, 10)
    m2 = np.array([1, 1, 0, 1, 1], bool)
    f3 = np.arange(2, 4)
    tracks = [_track_rows(rng, 1, f1, m1), _track_rows(rng, 2, f2, m2),
              _track_rows(rng, 3, f3, np.ones(2, bool))]
    frames, sizes = _frames(tracks)
    out = smooth_tracks(frames, sizes, config)
    for t in tracks:
        tid = next(iter(t.values()))[0]
        got_xy = np.array([f.filtered_xy[f.track_id == tid][0] for f in out if tid in f.track_id])
        got_v = np.array([f.velocity[f.track_id == tid][0] for f in out if tid in f.track_id])
        got_wh = np.array([f.wh[f.track_id == tid][0] for f in out if tid in f.track_id])
        refs = _filterpy_position(t, config)
        for axis in (0, 1):
            ref = refs[axis]
            np.testing.assert_allclose(got_xy[:, axis], ref[:, 0], rtol=1e-9, atol=1e-7)
            np.testing.assert_allclose(got_v[:, axis] * fps, ref[:, 1], rtol=1e-9, atol=1e-7)
            np.testing.assert_allclose(np.log(got_wh[:, axis]), _filterpy_size(t, axis, config),
                                       rtol=1e-9, atol=1e-9)
    # everything else is kept
    for a, b in zip(frames, out, strict=True):
        assert a.frame == b.frame
        np.testing.assert_array_equal(a.track_id, b.track_id)
        np.testing.assert_array_equal(a.det_index, b.det_index)
        np.testing.assert_array_equal(a.measured_xy, b.measured_xy)


def test_rows_without_public_id_are_left_alone() -> None:
    rng = np.random.default_rng(0)
    rows = _track_rows(rng, -1, np.arange(4), np.ones(4, bool))
    frames, sizes = _frames([rows])
    out = smooth_tracks(frames, sizes, TrackerConfig())
    for a, b in zip(frames, out, strict=True):
        np.testing.assert_array_equal(a.filtered_xy, b.filtered_xy)
        np.testing.assert_array_equal(a.wh, b.wh)


def _iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    lo = np.maximum(a[:, :2] - a[:, 2:] / 2, b[:, :2] - b[:, 2:] / 2)
    hi = np.minimum(a[:, :2] + a[:, 2:] / 2, b[:, :2] + b[:, 2:] / 2)
    inter = np.clip(hi - lo, 0, None).prod(axis=1)
    return inter / (a[:, 2:].prod(axis=1) + b[:, 2:].prod(axis=1) - inter)


@pytest.mark.parametrize("fps", [5.0, 10.0, 30.0])
def test_smoothing_puts_a_walkers_jittery_boxes_closer_to_the_truth(fps: float) -> None:
    """A walker at 1.2 box widths/s whose detector boxes are off by 10 % of their size and
    now and then 1.7 times too wide: the smoothed rows overlap the true box more than the
    filtered ones, at every frame rate, and more rows pass IoU 0.5."""
    rng = np.random.default_rng(11)
    n = int(4 * fps)
    t = np.arange(n) / fps
    true_wh = np.array([40.0, 100.0])
    true_xy = np.stack([100 + 48 * t, 300 + 5 * np.sin(t)], axis=1)
    xy = true_xy + rng.normal(0, 0.1, (n, 2)) * true_wh
    wh = true_wh * np.exp(rng.normal(0, 0.1, (n, 2)))
    wide = rng.random(n) < 0.15
    wh[wide, 0] *= 1.7
    frames = [Detections(k, xy[k : k + 1], wh[k : k + 1], np.array([1.0])) for k in range(n)]
    config = TrackerConfig(fps=fps)

    def overlap(smooth: bool) -> np.ndarray:
        c = track_detections(frames, config, smooth=smooth).columns()
        assert set(c["track_id"].tolist()) == {1}
        k = c["frame"]
        return _iou(np.hstack([c["filtered_xy"], c["wh"]]),
                    np.hstack([true_xy[k], np.broadcast_to(true_wh, (k.size, 2))]))

    raw, smoothed = overlap(False), overlap(True)
    assert smoothed.mean() > raw.mean() + 0.02
    assert smoothed.min() > raw.min()



def test_the_manoeuvring_mode_keeps_rows_on_their_cars_where_a_track_jumps() -> None:
    """A car at 3 fps, 40 px long, 30 px a frame, whose track jumps at frame 8 to the car 3
    lengths ahead (a wrong association a low frame rate makes): with the two modes the jump
    is a manoeuvre and every smoothed row stays on the box it measured; with the steady
    mode alone (both modes' noise the same) the rows around the jump are pulled off both
    cars, by more than half a car."""
    rng = np.random.default_rng(5)
    fps, n = 3.0, 16
    k = np.arange(n)
    x = 20 + 30.0 * k + np.where(k >= 8, 120.0, 0.0) + rng.normal(0, 1.0, n)
    box = np.array([40.0, 22.0])
    rows = {int(f): (1, int(TrackState.CONFIRMED), int(f), np.array([x[f], 200.0]),
                     np.array([x[f], 200.0]), box, box) for f in k}
    frames, sizes = _frames([rows])
    config = TrackerConfig(fps=fps)

    def off_by(c: TrackerConfig) -> np.ndarray:
        out = smooth_tracks(frames, sizes, c)
        return np.abs(np.array([f.filtered_xy[0, 0] for f in out]) - x) / box[0]

    two_modes = off_by(config)
    steady = off_by(config.replace(manoeuvre_noise=config.accel_noise))
    assert two_modes.max() < 0.25
    assert steady.max() > 0.5
