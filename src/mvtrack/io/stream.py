"""Text files that grow while a run goes on, valid at every moment.

:class:`LineAppender` is the streaming counterpart of :func:`mvtrack.io.atomic.atomic_path`:
the file is created whole (empty, or with its header line) by a rename, then each batch of
complete lines is appended with one ``write`` call and made durable with ``fsync``. A reader
sees the file end after a whole line: the old content, or the old content and whole new
lines (the one ``write`` of a batch is retried only for the rest of a short write, and the
rest is kept and written first by the next call or by :meth:`LineAppender.close`, so an
interrupted batch is completed, never left as a half line).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from mvtrack.io.atomic import write_text


class LineAppender:
    """Append whole lines to ``path``, flushed and synced at each :meth:`append`.

    Parameters
    ----------
    path : path
        The file; created (replacing any file of that name) with ``header`` as its content.
    header : str
        First line(s) of the file, ending with a newline (``""``: the file starts empty).

    Raises
    ------
    OSError
        The file cannot be created or opened for appending, or is not a regular file (a
        pipe or a device cannot be kept valid as a file).
    """

    def __init__(self, path: str | os.PathLike[str], header: str = "") -> None:
        if header and not header.endswith("\n"):
            raise ValueError("LineAppender: the header must end with a newline")
        self.path = Path(path)
        write_text(self.path, header)  # whole, by a rename
        self._fd: int | None = os.open(self.path, os.O_WRONLY | os.O_APPEND)
        if not stat.S_ISREG(os.fstat(self._fd).st_mode):
            os.close(self._fd)
            self._fd = None
            raise OSError(f"{self.path}: not a regular file; streamed results need one")
        self._pending = b""
        self.lines = 0  #: lines appended so far (the header not counted)

    def append(self, text: str) -> None:
        """Append ``text`` (complete lines, each ending with a newline) and sync the file."""
        if text and not text.endswith("\n"):
            raise ValueError("LineAppender.append: text must end with a newline")
        if self._fd is None:
            raise ValueError(f"{self.path}: appending to a closed file")
        data = text.encode("utf-8")
        self.lines += data.count(b"\n")
        self._pending += data
        self._write_pending()

    def _write_pending(self) -> None:
        fd = self._fd
        assert fd is not None
        while self._pending:
            n = os.write(fd, self._pending)  # one call for the whole batch, as a rule
            self._pending = self._pending[n:]
        os.fsync(fd)

    def close(self) -> None:
        """Write what an interrupted :meth:`append` left, sync and close (idempotent)."""
        if self._fd is None:
            return
        try:
            self._write_pending()
        finally:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> LineAppender:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
