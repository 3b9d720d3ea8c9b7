"""Exceptions that the command line turns into a one-line message and a non-zero exit."""

from __future__ import annotations


class InputError(ValueError):
    """Bad user input: a missing or unreadable file, malformed rows, an unknown option.

    The message is a complete sentence that names the problem (and the file and line where
    there is one); the CLI prints it as ``error: <message>`` and exits with status 2.
    """
