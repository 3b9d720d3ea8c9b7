"""HOTA from TrackEval 1.3.0 (MIT licence, ``LICENSE`` here), the files it needs, verbatim.

``metrics/hota.py``, ``metrics/_base_metric.py``, ``_timing.py`` and ``utils.py`` are the
files of the ``trackeval-1.3.0-py3-none-any.whl`` wheel on PyPI, unchanged; :data:`FILES`
holds their SHA-256 as that wheel's ``RECORD`` lists them, and the tests check every file
against it. Only the two ``__init__.py`` files are mvtrack's: they import what HOTA needs and
nothing else (TrackEval's own import the dataset loaders, plotting and the other metrics).

Why a copy in the tests rather than a test dependency: every TrackEval release on PyPI (1.0.0
to 1.3.0) and its SoccerNet fork declare ``opencv-python``, which installs a second ``cv2`` over
the ``opencv-contrib-python-headless`` that mvtrack uses (and needs libGL); pip offers no way to
drop one dependency of a package. ``mvtrack.eval.hota`` computes HOTA on the sparse list of
overlapping boxes (memory bounded for thousands of targets); this copy is the independent
reference it is tested against, where the TrackEval package itself is not installed.
"""

#: SHA-256 (URL-safe base64, as in a wheel's RECORD) of each verbatim file.
FILES: dict[str, str] = {
    "_timing.py": "tRgOI39VThh7Ks2Ig2aLI5zvh5bUpr5ufRxmMWrObFE",
    "utils.py": "i4XuH_3bjAgc8apdVB0xrjdda3lc1t4vNHI80nIrgmc",
    "metrics/_base_metric.py": "TGcCZFI2B2iZDYzqk_VjKPHgInk8NdNqXoLfNpsP1Ws",
    "metrics/hota.py": "7sOp6CJDVHfATuW4KyfH1wl3_7lLr4OK_lS125YDYrs",
}

__version__ = "1.3.0"
