"""Output folders that hold one run: the earlier run's files never linger beside the new ones.

``mvtrack track``, ``demo``, ``simulate`` and ``batch`` write into a folder (``--out``). When
that folder already holds an earlier run, keeping its files beside the new ones would mix two
runs (an old ``tracks.mp4``, ``report.html`` or snapshot beside a new ``results.txt``).
:func:`run_folder` makes the folder belong to the new run, as build tools treat their output
folders:

- a folder that does not exist, or is empty, is used as it is;
- a folder that holds an earlier run of the same command (a run's summary, and only files
  mvtrack writes) is moved aside when the new run starts and deleted when it has finished;
  if the new run fails before it finishes (a bad setting found late, an unreadable file),
  its partial files are removed and the earlier run is put back, untouched;
- a folder that holds anything else (files mvtrack did not write, or another command's run)
  is refused with one line, unless ``force``: then the run writes into it, its files
  replacing those of the same names and the others kept.

Nothing is ever deleted that mvtrack did not write, and a folder that holds one of the run's
inputs (``mvtrack track out/video.mp4 --out out``) is never moved.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import uuid
from collections.abc import Iterable, Iterator
from pathlib import Path

from mvtrack.errors import InputError

#: files that mvtrack's commands write into an output folder
OUTPUT_NAMES = frozenset({
    # mvtrack track (and each video of mvtrack batch)
    "results.txt", "states.csv", "summary.json", "tracks.mp4", "trajectories.png",
    # analytics: mvtrack track with [analytics], mvtrack analyze, mvtrack report
    "counts.csv", "movements.csv", "speeds.csv", "tracks.csv", "analytics.json",
    "report.html",
    # mvtrack demo
    "gt.txt", "metrics.json", "track_lengths.png", "tracks_per_frame.png",
    # mvtrack simulate
    "det.txt", "video.mp4", "scene.json",
    # mvtrack batch
    "batch.json",
})
#: snapshots (``--snapshot N``) and the temporary files of the atomic writers
_PATTERNS = (re.compile(r"frame\d{5,}\.png"), re.compile(r"\..+\..*"))
#: the file that says a folder is a run's, and keys it always has
_MARKERS = {
    "batch.json": ("videos", "total", "settings"),
    "scene.json": ("scene", "seed", "fps", "frames"),
    "summary.json": ("source", "frames", "video_fps", "files"),
}


def _is_output_name(name: str) -> bool:
    return name in OUTPUT_NAMES or any(p.fullmatch(name) for p in _PATTERNS)


def run_kind(folder: Path) -> str | None:
    """The command whose run ``folder`` holds, by its summary (``batch``, ``simulate``,
    ``demo``, ``track``), or None."""
    for name, keys in _MARKERS.items():
        path = folder / name
        if not path.is_file():
            continue
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, ValueError):
            continue
        if isinstance(data, dict) and all(k in data for k in keys):
            if name == "summary.json":
                return "demo" if (folder / "metrics.json").is_file() else "track"
            return {"scene.json": "simulate", "batch.json": "batch"}[name]
    return None


#: the first line of a MOTChallenge results file as mvtrack writes it
_RESULTS_ROW = re.compile(r"\d+,-?\d+(,-?\d+\.\d+){4},[-+.\deE]+,-1,-1,-1")


def _results_only(folder: Path) -> bool:
    """Whether ``folder`` holds only results files as ``mvtrack track-detections`` writes
    them (``<sequence>.txt``, MOTChallenge rows ending in -1,-1,-1), or nothing."""
    for p in folder.iterdir():
        if not (p.is_file() and p.suffix == ".txt") and not _PATTERNS[1].fullmatch(p.name):
            return False
        if p.suffix == ".txt":
            try:
                with p.open(encoding="utf-8") as fh:
                    first = fh.readline().strip()
            except (OSError, UnicodeDecodeError):
                return False
            if first and not _RESULTS_ROW.fullmatch(first):
                return False
    return True


def foreign_entries(folder: Path) -> list[str]:
    """Names in ``folder`` that are not an earlier mvtrack run's (empty: it is one, or empty).

    A folder is an earlier run when it has a run's summary (``summary.json``, ``scene.json``
    or ``batch.json`` as mvtrack writes them) and every entry is a file mvtrack writes or a
    sub-folder made from it: itself an earlier run (the videos of a batch, a run inside a
    simulated scene's folder) or a folder of ``mvtrack track-detections`` results. Any entry
    in a folder without such a summary is foreign.
    """
    entries = sorted(folder.iterdir(), key=lambda p: p.name)
    if not entries:
        return []
    if run_kind(folder) is None:
        return [p.name for p in entries]
    out = []
    for p in entries:
        if p.is_dir() and not p.is_symlink():
            if foreign_entries(p) and not _results_only(p):
                out.append(p.name + "/")
        elif not _is_output_name(p.name):
            out.append(p.name)
    return out


def _quote(names: list[str], limit: int = 3) -> str:
    shown = ", ".join(repr(n) for n in names[:limit])
    return shown + (f" and {len(names) - limit} more" if len(names) > limit else "")


def check_folder(out: Path, option: str = "--out") -> None:
    """Refuse an ``out`` that is a file, or lies below one (one line naming ``option``)."""
    if out.exists() and not out.is_dir():
        raise InputError(f"{option} {out} is a file, not a folder")
    for parent in out.parents:
        if parent.exists():
            if not parent.is_dir():
                raise InputError(f"{option} {out}: {parent} is a file, not a folder")
            break


def make_folder(out: Path, option: str = "--out") -> None:
    """Create ``out`` (and its parents), or say in one line naming ``option`` why not."""
    check_folder(out, option)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        parent = next((p for p in out.parents if p.exists()), None)
        if isinstance(exc, FileNotFoundError) and parent is not None:
            # /proc, /sys and the like exist but take no new folders
            raise InputError(f"{option} {out}: cannot create a folder in {parent} "
                             "(it takes no new folders)") from None
        raise InputError(f"{option} {out}: cannot create the folder "
                         f"({exc.strerror or exc})") from None
    if not os.access(out, os.W_OK | os.X_OK):
        raise InputError(f"{option} {out}: the folder is not writable")


def _inside(path: Path, folder: Path) -> bool:
    try:
        path.resolve().relative_to(folder.resolve())
    except (ValueError, OSError):
        return False
    return True


@contextlib.contextmanager
def run_folder(
    out: str | os.PathLike[str], *, force: bool = False, inputs: Iterable[str] = (),
    option: str = "--out", kind: str | None = None,
) -> Iterator[Path]:
    """The folder ``out``, holding only the files of the run in the ``with`` block.

    The folder is checked when the block is entered (before any work), so a bad ``--out``
    ends the command at once with one line; see the module docstring for what happens to an
    earlier run in it.

    Parameters
    ----------
    out : path
        The output folder.
    force : bool
        Write into a folder that holds files mvtrack did not write (they are kept).
    inputs : iterable of str
        Files the run reads (videos, detection files). A folder holding one is never moved
        aside; without ``force`` it is refused.
    option : str
        The option that named ``out``, for the messages.
    kind : str, optional
        The command of this run (``track``, ``demo``, ``simulate``, ``batch``): a folder
        holding another command's run is not replaced (refused, or written into with
        ``force``).

    Raises
    ------
    InputError
        ``out`` is a file or lies below one, cannot be created or written, holds files that
        mvtrack did not write (without ``force``), or holds one of ``inputs``.
    """
    out = Path(out)
    check_folder(out, option)
    held = [str(p) for p in inputs if "://" not in str(p) and Path(p).exists()
            and out.is_dir() and _inside(Path(p), out)]
    if held and not force:
        raise InputError(f"{option} {out} holds the input {held[0]}: choose another folder "
                         "(or add --force to write beside it)")
    created = not out.exists()
    make_folder(out, option)
    aside: Path | None = None
    if any(out.iterdir()) and not held:
        foreign = foreign_entries(out)
        found = None if foreign else run_kind(out)
        if foreign and not force:
            raise InputError(
                f"{option} {out} is not empty and is not the folder of an earlier mvtrack run "
                f"({_quote(foreign)}): choose a new or empty folder, or add --force to write "
                "into it (files of the same names are replaced, the others kept)")
        if kind is not None and found not in (None, kind) and not force:
            raise InputError(
                f"{option} {out} holds a run of mvtrack {found}, not of mvtrack {kind}: "
                "choose another folder, or add --force to write into it")
        if not foreign and (kind is None or found == kind):  # an earlier run: moved aside
            aside = _move_aside(out, option)  # now, deleted once this one is done
    fresh = aside is not None or not any(out.iterdir())
    try:
        yield out
    except BaseException:
        if fresh:  # nothing of the failed run is kept; the earlier run comes back
            _clear(out, keep=aside)
            if aside is not None:
                _move_back(aside, out)
            elif created:
                with contextlib.suppress(OSError):
                    out.rmdir()
        raise
    if aside is not None:
        shutil.rmtree(aside, ignore_errors=True)


def _move_aside(out: Path, option: str) -> Path:
    """Move every entry of ``out`` into a new hidden sub-folder of it; return that folder.

    The folder itself stays where it is (it may be the working directory of the shell).
    """
    aside = out / f".earlier-run-{uuid.uuid4().hex[:8]}"
    try:
        aside.mkdir()
        for p in list(out.iterdir()):
            if p != aside:
                os.rename(p, aside / p.name)
    except OSError as exc:
        if aside.exists():
            _move_back(aside, out)
        raise InputError(f"{option} {out}: cannot replace the earlier run in it "
                         f"({exc.strerror or exc})") from None
    return aside


def _clear(out: Path, keep: Path | None) -> None:
    for p in list(out.iterdir()):
        if p == keep:
            continue
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
        else:
            with contextlib.suppress(OSError):
                p.unlink()


def _move_back(aside: Path, out: Path) -> None:
    for p in list(aside.iterdir()):
        with contextlib.suppress(OSError):
            os.rename(p, out / p.name)
    with contextlib.suppress(OSError):
        aside.rmdir()
