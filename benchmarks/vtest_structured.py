"""Structured KF vs a plain KF on one person of vtest.avi through a crossing (paper 3, real video).

One person is picked at ``--start`` by a point inside their foreground blob. Foreground: OpenCV
MOG2 (history 300, shadows removed), opening 3×3, closing 9×9; blobs ≥ 400 px.

- **Plain KF** (CA, SPEC §3.3 noise, whole object): each frame it takes the nearest blob whose
  centre lies inside its predicted box (last size, sides × 1.5) and is updated with the blob's
  box centre; it coasts when there is none. When two people merge into one blob, that blob is
  what it sees.
- **SKF** (SPEC §3.3 defaults or ``--model cv``): the person's box is cut into three bands —
  head (top 18 %), torso (18–55 %), legs (55–100 %) — each with a colour model (mean and
  spread of its BGR foreground pixels at the start). Each frame, each part is measured as the
  centroid of the foreground pixels inside its predicted band box whose colour is within
  ``--colour-tol`` standard deviations of its model; α of eq. (16) from the SPEC §3.3 features
  of those pixels against the previous frame (α = 1 under 5 % of the start area).

Prints the positions of both per frame, and writes a montage of crops with both boxes
(``--png``) for the documentation.

    python benchmarks/vtest_structured.py --video ../shared/data/vtest.avi --start 466 \\
        --end 505 --point 556 262 --png docs/images/structured-vtest.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

from mvtrack.detection.parts import bgr_to_hsi, feature_distance, occlusion_degree
from mvtrack.detection.parts import region_features as features
from mvtrack.filters import kalman
from mvtrack.filters.structured import PartGraph, SKFParams, init, predict, update

BANDS = ((0.0, 0.18), (0.18, 0.55), (0.55, 1.0))


def foreground(video: str, end: int):
    """Frames and cleaned MOG2 masks for frames 0 … end."""
    cap = cv2.VideoCapture(video)
    if not cap.isOpened():
        raise OSError(f"cannot open video {video}")
    mog = cv2.createBackgroundSubtractorMOG2(history=300, varThreshold=25, detectShadows=True)
    k3, k9 = np.ones((3, 3), np.uint8), np.ones((9, 9), np.uint8)
    for k in range(end + 1):
        ok, frame = cap.read()
        if not ok:
            break
        m = (mog.apply(frame) == 255).astype(np.uint8)
        m = cv2.morphologyEx(cv2.morphologyEx(m, cv2.MORPH_OPEN, k3), cv2.MORPH_CLOSE, k9)
        yield k, frame, m


def blobs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Box centres (M, 2) and boxes (M, 4) x, y, w, h of components ≥ 400 px."""
    _, _, st, _ = cv2.connectedComponentsWithStats(mask)
    st = st[1:][st[1:, 4] >= 400]
    return st[:, :2] + st[:, 2:4] / 2.0, st[:, :4].astype(float)


def part_pixels(frame, mask, centre, wh, model, tol):
    """Label image (crop) of pixels matching each part's colour inside its predicted box."""
    H, W = mask.shape
    lab = np.zeros((H, W), np.int32)
    for j in range(3):
        if not np.all(np.isfinite(centre[j])):
            continue
        x0, y0 = np.floor(centre[j] - wh[j] / 2).astype(int)
        x1, y1 = np.ceil(centre[j] + wh[j] / 2).astype(int)
        x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, W), min(y1, H)
        if x1 <= x0 or y1 <= y0:
            continue
        c = frame[y0:y1, x0:x1].astype(float)
        mean, sd = model[j]
        near = np.all(np.abs(c - mean) <= tol * sd, axis=-1) & (mask[y0:y1, x0:x1] > 0)
        sub = lab[y0:y1, x0:x1]
        sub[near & (sub == 0)] = j + 1
    return lab


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--video", default="../shared/data/vtest.avi")
    ap.add_argument("--start", type=int, required=True)
    ap.add_argument("--end", type=int, required=True)
    ap.add_argument("--point", type=float, nargs=2, required=True, help="x y inside the person")
    ap.add_argument("--model", choices=["ca", "cv"], default="ca")
    ap.add_argument("--colour-tol", type=float, default=2.5)
    ap.add_argument("--png", type=Path, default=None)
    ap.add_argument("--every", type=int, default=4)
    ap.add_argument(
        "--alpha",
        choices=["spec", "achromatic"],
        default="spec",
        help="spec: |ΔF| of SPEC §3.3; achromatic: without the hue term for parts whose mean "
        "saturation is < 0.15 (their hue is noise), and |ΔF| divided by --alpha-scale",
    )
    ap.add_argument("--alpha-scale", type=float, default=1.0)
    ap.add_argument("--window", type=int, nargs=4, default=None, help="montage crop x0 y0 x1 y1")
    args = ap.parse_args()
    params = SKFParams(model=args.model)
    graph = PartGraph.chain(3)
    kf = skf = None
    rows, shots = [], []
    prev_f = None
    for k, frame, mask in foreground(args.video, args.end):
        if k < args.start:
            continue
        centres, boxes = blobs(mask)
        if k == args.start:
            inside = (
                (boxes[:, 0] <= args.point[0])
                & (args.point[0] <= boxes[:, 0] + boxes[:, 2])
                & (boxes[:, 1] <= args.point[1])
                & (args.point[1] <= boxes[:, 1] + boxes[:, 3])
            )
            if not inside.any():
                raise ValueError(f"no foreground blob contains {args.point} at frame {k}")
            x, y, w, h = boxes[np.flatnonzero(inside)[0]]
            size = np.array([w, h])
            start_c = np.array([x + w / 2, y + h / 2])
            part_wh = np.array([[w, (b - a) * h] for a, b in BANDS])
            part_c = np.array([[x + w / 2, y + (a + b) / 2 * h] for a, b in BANDS])
            model = []
            for a, b in BANDS:
                y0, y1 = int(y + a * h), int(y + b * h)
                px = frame[y0:y1, int(x) : int(x + w)][mask[y0:y1, int(x) : int(x + w)] > 0]
                model.append((px.mean(axis=0), np.maximum(px.std(axis=0), 8.0)))
            ref_area = np.array(
                [
                    (part_pixels(frame, mask, part_c, part_wh, model, args.colour_tol) == j).sum()
                    for j in (1, 2, 3)
                ]
            )
            kx = np.zeros((1, params.n))
            kx[0, :2] = [x + w / 2, y + h / 2]
            kP = params.P0(params.r_cell)[None]
            kf = (kx, kP)
            skf = init(params, graph, part_c[None])
            hue, sat, inten = bgr_to_hsi(frame)
            lab = part_pixels(frame, mask, part_c, part_wh, model, args.colour_tol)
            prev_f = features(lab, 3, hue, sat, inten)
            part_sat = np.array([sat[lab == j].mean() for j in (1, 2, 3)])
            rows.append((k, *kx[0, :2], *part_c.mean(axis=0), 0, 0, 0))
            continue
        # plain KF: nearest blob inside the predicted box
        kx, kP = kalman.predict(*kf, params.F, params.Q)
        pred = kx[0, :2]
        d = np.abs(centres - pred)
        ok = np.all(d <= size * 0.75, axis=1)
        z = np.full((1, 2), np.nan)
        if ok.any():
            z[0] = centres[np.flatnonzero(ok)[np.argmin(np.linalg.norm(d[ok], axis=1))]]
        kf = kalman.update(kx, kP, z, params.H, params.R_cell)
        # SKF: colour-matched pixels inside each predicted part box
        skf = predict(params, skf)
        pc = skf.xc[0, :, :2]
        hue, sat, inten = bgr_to_hsi(frame)
        lab = part_pixels(frame, mask, pc, part_wh, model, args.colour_tol)
        f = features(lab, 3, hue, sat, inten)
        seen = f.area >= 0.05 * ref_area
        zp = np.where(seen[:, None], f.centroid, np.nan)
        was = prev_f.area >= 0.05 * ref_area
        dF = np.diag(feature_distance(prev_f, f))
        if args.alpha == "achromatic":
            grey = (part_sat < 0.15) & np.isfinite(dF)
            dh = np.abs((prev_f.hue - f.hue + 180.0) % 360.0 - 180.0) / 20.0
            dF = np.where(grey, dF - np.nan_to_num(dh), dF) / args.alpha_scale
        alpha = np.where(seen & was, occlusion_degree(dF), 1.0)  # eq. (16)
        skf, _ = update(params, graph, skf, zp[None], alpha[None])
        prev_f = f
        obj = skf.xc[0, :, :2].mean(axis=0)
        rows.append((k, *kf[0][0, :2], *obj, *alpha))
        if (k - args.start) % args.every == 0:
            shots.append((k, frame.copy(), kf[0][0, :2].copy(), skf.xc[0, :, :2].copy()))
    print("frame  KF_x  KF_y  SKF_x  SKF_y  alpha_head alpha_torso alpha_legs")
    for r in rows:
        print(
            f"{r[0]:5d} {r[1]:6.1f} {r[2]:6.1f} {r[3]:6.1f} {r[4]:6.1f}  "
            f"{r[5]:.2f} {r[6]:.2f} {r[7]:.2f}"
        )
    if args.png and shots:
        tiles = []
        for k, frame, kpos, parts in shots:
            img = frame.copy()
            w, h = size
            p0 = (kpos - size / 2).astype(int)
            cv2.rectangle(img, tuple(p0), tuple((kpos + size / 2).astype(int)), (0, 0, 255), 2)
            for j in range(3):
                q0 = (parts[j] - part_wh[j] / 2).astype(int)
                q1 = (parts[j] + part_wh[j] / 2).astype(int)
                cv2.rectangle(img, tuple(q0), tuple(q1), (255, 200, 0), 1)
            if args.window:
                x0, y0, x1, y1 = args.window
            else:
                x0, y0 = int(max(start_c[0] - 90, 0)), int(max(start_c[1] - 110, 0))
                x1, y1 = x0 + 220, y0 + 260
            crop = img[y0:y1, x0:x1].copy()
            cv2.putText(crop, str(k), (3, 14), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
            tiles.append(crop)
        hmin = min(t.shape[0] for t in tiles)
        montage = np.hstack([t[:hmin] for t in tiles])
        args.png.parent.mkdir(parents=True, exist_ok=True)
        from mvtrack.io.atomic import atomic_path

        with atomic_path(args.png) as tmp:
            cv2.imwrite(str(tmp) + ".png", montage)
            Path(str(tmp) + ".png").replace(tmp)
        print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
