"""Paper 2's group of three people splitting behind a parked car, among others (SPEC X8)."""

from __future__ import annotations

import numpy as np

from mvtrack.sim.intersection import X5_COLORS
from mvtrack.sim.scene import Scene, assemble


# ---------------------------------------------------------------------- X8
def x8_splitting_group(seed: int | np.random.Generator = 0, car_depth: bool = True) -> Scene:
    """Paper 2's group of three people splitting behind a car, plus 11 others (SPEC X8).

    320×240, 15 fps, 240 frames. A static white car 44×22 px centred at (96, 64) is an
    occluder (``meta["occluders"]``) in front of the people that hides at most the lower half
    of each (``hides = "lower half"``: people walk behind a parked car, which covers their legs
    and not their heads, SPEC X8 as revised), so the group stays visible while it splits. P1–P3
    (ids 1–3, category ``group``) start at (18, 12) with v = (1.2, 0.8), side by side ±9 px
    across the direction of motion (P1 on the upper-right side), 8×16 px, so their blobs
    merge. With ``car_depth`` False the car hides the lower half of everyone over it, also of
    people whose feet are already below its lower edge (a variant of the [R] geometry). At
    frame 60 (split point (90, 60), over the car) they change velocity: P1
    (1.44, 0.46), P2 (0.25, 1.4), P3 (−0.15, 1.4). Their colours differ from the paving by
    ≥ 40 grey levels of luma, so each person's visible upper half is one blob. Eleven others
    on straight lines, kept ≥ 30 px (centre distance) from every group member, ≥ 24 px from
    one another and clear of the car: 6 ``car`` (28×12 px, 3–5 px/frame), 2 ``motorcycle``
    (12×8 px, 4–6), 3 ``pedestrian`` (8×16 px, 1–1.5).
    """
    rng = np.random.default_rng(seed)
    n_frames, size = 240, (320, 240)
    t = np.arange(n_frames, dtype=np.float64)
    v0 = np.array([1.2, 0.8])
    d = v0 / np.linalg.norm(v0)
    across = np.array([d[1], -d[0]])  # right-and-up across the direction of motion
    start = np.array([18.0, 12.0]) + np.outer([9.0, 0.0, -9.0], across)  # P1, P2, P3
    v1 = np.array([[1.44, 0.46], [0.25, 1.4], [-0.15, 1.4]])
    tt = t[:, None, None]
    at60 = start + 60.0 * v0
    group = np.where(tt < 60, start + tt * v0, at60 + (tt - 60.0) * v1)  # (F, 3, 2)
    group_hd = np.where(t[:, None] < 60, np.arctan2(v0[1], v0[0]), np.arctan2(v1[:, 1], v1[:, 0]))
    # a light cabin: the people's upper halves (luma 64–73, skin 169) stand out against every
    # part of the car they pass in front of
    occ = {"xy": (96.0, 64.0), "wh": (44.0, 22.0), "color": (245, 245, 245),
           "color2": (205, 205, 200), "hides": "lower half", "depth": bool(car_depth)}
    occ_lo = np.array(occ["xy"]) - np.array(occ["wh"]) / 2 - 4.0
    occ_hi = np.array(occ["xy"]) + np.array(occ["wh"]) / 2 + 4.0

    others = [("car", 28.0, 12.0, 3.0, 5.0)] * 6 + [("motorcycle", 12.0, 8.0, 4.0, 6.0)] * 2
    others += [("pedestrian", 8.0, 16.0, 1.0, 1.5)] * 3
    n = 3 + len(others)
    xy = np.full((n_frames, n, 2), np.nan)
    hd = np.zeros((n_frames, n))
    xy[:, :3], hd[:, :3] = group, group_hd
    body = np.zeros((n, 2))
    body[:3] = (8.0, 16.0)
    img = np.array(size, float)
    for j, (cat, length, width, vlo, vhi) in enumerate(others):
        i = 3 + j
        body[i] = (length, width)
        half = max(length, width) / 2
        for _attempt in range(5000):
            spd = rng.uniform(vlo, vhi)
            if cat == "pedestrian":  # enter at a random edge point, heading inwards ±60°
                edge = int(rng.integers(4))
                inward = [0.0, np.pi / 2, np.pi, -np.pi / 2][edge]
                ang = inward + rng.uniform(-np.pi / 3, np.pi / 3)
            else:  # vehicles drive along the image axes
                edge = int(rng.integers(4))
                ang = [0.0, np.pi / 2, np.pi, -np.pi / 2][edge]
            u = np.array([np.cos(ang), np.sin(ang)])
            lateral = rng.uniform(20.0, img[1 - edge % 2] - 20.0)
            p0 = np.empty(2)
            p0[edge % 2] = -half if edge < 2 else img[edge % 2] + half
            p0[1 - edge % 2] = lateral
            t0 = rng.uniform(0.0, 200.0)
            p = p0 + (t - t0)[:, None] * spd * u
            p[t < t0] = np.nan
            if np.any(np.all((p > occ_lo - half) & (p < occ_hi + half), axis=1)):
                continue  # would pass behind or over the static car
            dg = np.linalg.norm(group - p[:, None], axis=-1)
            if np.any(dg[np.isfinite(dg)] < 30.0):
                continue
            do = np.linalg.norm(xy[:, 3:i] - p[:, None], axis=-1)
            if np.any(do[np.isfinite(do)] < 24.0):
                continue
            xy[:, i], hd[:, i] = p, ang
            break
        else:  # pragma: no cover
            raise RuntimeError(f"x8_splitting_group: could not place target {i + 1} ({cat})")
    kinds = ["person"] * 3 + [
        "vehicle" if c == "car" else "motorcycle" if c == "motorcycle" else "person"
        for c, *_ in others
    ]
    # P1 red, P2 blue, P3 green: luma 65, 64, 73 against the paving's 118
    people_colors = np.array(
        [[20, 20, 170], [200, 60, 20], [20, 110, 20], [20, 20, 20], [220, 220, 60],
         [40, 200, 230], [180, 40, 160], [240, 240, 240], [0, 120, 255]], np.uint8)
    color = np.zeros((n, 3), np.uint8)
    color[:3] = people_colors[:3]
    color[3:] = np.concatenate([X5_COLORS[[3, 4, 6, 1, 9, 2]], X5_COLORS[[3, 8]],
                                people_colors[[3, 4, 5]]])
    return assemble(
        "x8", 15, size, xy, hd,
        category=["group"] * 3 + [c for c, *_ in others], kind=kinds, body=body,
        rotates=np.array([k in ("vehicle", "motorcycle") for k in kinds]), color=color,
        meta={"occluders": [occ], "group_ids": (1, 2, 3), "split_frame": 60,
              "split_point": (90.0, 60.0)},
    )
