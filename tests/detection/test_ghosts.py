"""The disturbance map's ghosts (``ghost_every``, not in paper 1): a vehicle that stood long
enough to be absorbed into the running average leaves a blob where it stood when it drives
off; with the ghost test that blob is gone within a frame or two and the vehicle's own blob
stays, without it the ghost lasts for tens of frames."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.detection import make_detector


def _scene(n_stand: int = 300, n_go: int = 30) -> list[np.ndarray]:
    """A textured road; a bright 16×10 vehicle stands at x = 40 … 56, then drives right
    at 3 px per frame."""
    rng = np.random.default_rng(0)
    road = (60 + rng.integers(0, 20, (60, 160))).astype(np.uint8)
    frames = []
    for k in range(n_stand + n_go):
        img = road.copy()
        x = 40 + max(0, k - n_stand) * 3
        img[25:35, x : x + 16] = 220
        frames.append(np.dstack([img] * 3))
    return frames


def _ghost_frames(every: int) -> tuple[int, list[int]]:
    det = make_detector("disturbance-map", ghost_every=every, close_size=3, min_area=20.0)
    frames = _scene()
    ghost_seen, moving = 0, []
    for k, f in enumerate(frames):
        d = det(f)
        if k <= 300 + 8:
            continue
        at_home = [(x, y) for x, y in d.xy if 36 <= x <= 60 and 20 <= y <= 40]
        ghost_seen += bool(at_home)
        moving.append(int(any(x > 70 for x, _ in d.xy)))
    return ghost_seen, moving


def test_the_ghost_test_removes_the_place_a_standing_vehicle_left() -> None:
    with_test, moving = _ghost_frames(1)
    without, moving0 = _ghost_frames(0)
    assert without >= 15  # the ghost lasts: paper 1's running average (β = 0.02)
    assert with_test <= 2
    assert all(moving[5:]) and all(moving0[5:])  # the vehicle itself is detected either way


@pytest.mark.parametrize("bad", [-1, 1.5, True, "5"])
def test_ghost_every_must_be_a_whole_number_of_frames(bad) -> None:
    with pytest.raises(ValueError, match="ghost_every"):
        make_detector("disturbance-map", ghost_every=bad)
