"""Exceptions and warnings that the command line turns into one-line messages."""

from __future__ import annotations

import contextlib
import sys
import warnings
from collections.abc import Iterator
from typing import TextIO


class InputError(ValueError):
    """Bad user input: a missing or unreadable file, malformed rows, an unknown option.

    The message is a complete sentence that names the problem (and the file and line where
    there is one); the CLI prints it as ``error: <message>`` and exits with status 2.
    """


class InputWarning(UserWarning):
    """Input that is valid but suspicious, such as a detection file without rows.

    The work goes on; the CLI prints the message as one line ``warning: <message>``.
    """


@contextlib.contextmanager
def one_line_warnings(stream: TextIO | None = None) -> Iterator[None]:
    """Inside the block, show each :class:`InputWarning` as one line ``warning: <message>``.

    Other warnings keep Python's usual form. The command line runs every command in it.
    """
    out = sys.stderr if stream is None else stream
    with warnings.catch_warnings():
        warnings.simplefilter("always", InputWarning)
        shown = warnings.showwarning

        def show(message, category, filename, lineno, file=None, line=None):  # type: ignore[no-untyped-def]
            if issubclass(category, InputWarning):
                print(f"warning: {message}", file=out)
            else:
                shown(message, category, filename, lineno, file, line)

        warnings.showwarning = show
        yield
