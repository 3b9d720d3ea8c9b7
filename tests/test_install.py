"""The install: HOTA is always computed and equals TrackEval's, one cv2.

The README's two commands are plain ``pip install``s. These tests fail when what they install
stops working as a whole: HOTA silently missing (``None``), the reference copy of TrackEval
edited, or two OpenCV distributions writing the same ``cv2`` package.
"""

from __future__ import annotations

import base64
import hashlib
from importlib import metadata
from pathlib import Path

import motmetrics as mm
import pytest

import reference.trackeval as vendored
from mvtrack.eval.metrics import evaluate

TUD = Path(mm.__file__).parent / "data"

#: TrackEval 1.3.0's own pipeline (``trackeval.Evaluator`` with ``MotChallenge2DBox``,
#: BENCHMARK "MOT15", the package installed from PyPI) on motmetrics' TUD files: the mean over
#: α of each score. tests/eval/test_metrics.py runs that pipeline live where TrackEval is installed.
TRACKEVAL_1_3_0 = {
    "TUD-Campus": {
        "HOTA": 0.3913974378451139, "DetA": 0.418047030142763, "AssA": 0.36912068120832836,
        "LocA": 0.770052227022172, "DetRe": 0.4415774813077262, "DetPr": 0.7140825035561879,
        "AssRe": 0.38322491394349667, "AssPr": 0.754049776587294,
    },
    "TUD-Stadtmitte": {
        "HOTA": 0.3978490169927877, "DetA": 0.3922675723693166, "AssA": 0.4088407518112996,
        "LocA": 0.737521177178062, "DetRe": 0.4131305773083227, "DetPr": 0.6376220926147144,
        "AssRe": 0.4492190092628564, "AssPr": 0.6312033236759915,
    },
}

#: Distributions that install the ``cv2`` package; two of them overwrite each other's files.
OPENCV_DISTRIBUTIONS = (
    "opencv-python", "opencv-python-headless", "opencv-contrib-python",
    "opencv-contrib-python-headless",
)


@pytest.mark.parametrize("seq", sorted(TRACKEVAL_1_3_0))
def test_hota_is_computed_and_equals_trackeval(seq: str) -> None:
    scores = evaluate(TUD / seq / "gt.txt", TUD / seq / "test.txt")
    assert scores["notes"] == []
    for key, want in TRACKEVAL_1_3_0[seq].items():
        assert scores[key] is not None, f"{key} not computed"
        assert scores[key] == pytest.approx(want, abs=1e-12), key


def test_kept_trackeval_files_are_the_released_ones() -> None:
    root = Path(vendored.__file__).parent
    assert (root / "LICENSE").read_text().startswith("MIT License")
    for name, want in vendored.FILES.items():
        digest = hashlib.sha256((root / name).read_bytes()).digest()
        assert base64.urlsafe_b64encode(digest).rstrip(b"=").decode() == want, name


def test_exactly_one_opencv_distribution_is_installed() -> None:
    installed = []
    for name in OPENCV_DISTRIBUTIONS:
        try:
            metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
        installed.append(name)
    assert installed == ["opencv-contrib-python-headless"], (
        f"installed: {', '.join(installed) or 'none'}; these write the same cv2 package over "
        "each other. Keep only opencv-contrib-python-headless: pip uninstall the others, then "
        "pip install --force-reinstall --no-deps opencv-contrib-python-headless"
    )
