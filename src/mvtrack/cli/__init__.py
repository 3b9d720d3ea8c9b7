"""The ``mvtrack`` command line (Typer).

Every command lives in its own module and registers itself here. User errors
(:class:`~mvtrack.errors.InputError`, ``ValueError``, ``OSError``) and usage errors end in one
line ``error: ...`` on stderr and exit status 2; Ctrl-C ends with status 130, SIGTERM (as
``timeout``, ``docker stop`` or a batch scheduler send it) the same way with status 143
(:mod:`mvtrack.cli._signals`).
"""

from __future__ import annotations

import sys
from typing import Annotated

import typer

from mvtrack.cli import (
    _signals,
    batch,
    config,
    demo,
    evaluate,
    experiment,
    report,
    simulate,
    track,
    track_detections,
)
from mvtrack.errors import one_line_warnings

app = typer.Typer(
    name="mvtrack",
    help="Track many moving objects in fixed-camera video, and compare predictors honestly.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)


def _print_version(value: bool) -> None:
    if value:
        from mvtrack import __version__

        typer.echo(f"mvtrack {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_print_version, is_eager=True, help="Print the version and exit."
        ),
    ] = False,
    verbose: Annotated[
        bool, typer.Option("--verbose", help="Also show OpenCV's and FFmpeg's own messages.")
    ] = False,
) -> None:
    """Track many moving objects in fixed-camera video, and compare predictors honestly."""
    if verbose:
        from mvtrack.io.logs import set_verbose

        set_verbose()


for _module in (
    demo, track, track_detections, batch, evaluate, simulate, experiment, report, config,
):
    _module.register(app)

# Typer ships its own copy of Click; find its exception classes through a public name.
_CLICK_ERROR: type[Exception] = next(
    c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException"
)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``mvtrack`` console script; returns the exit status."""
    with _signals.sigterm_as_interrupt():
        try:
            status = _run(argv)
        except KeyboardInterrupt:  # a signal after the command returned
            status = _signals.EXIT_INTERRUPTED
        if status == _signals.EXIT_INTERRUPTED:
            # Typer turns an interrupt outside a command's own handling into a silent
            # exit status 130; say what happened in one line
            if not _signals.was_reported():
                print(f"error: {_signals.interrupt_word()}", file=sys.stderr)
            status = _signals.interrupt_status()
        return status


def _compiling() -> None:
    print("compiling mvtrack's kernels for this machine: once after an install or an upgrade,"
          " about half a minute", file=sys.stderr, flush=True)


def _run(argv: list[str] | None) -> int:
    from mvtrack.jit import on_first_compile

    on_first_compile(_compiling)
    command = typer.main.get_command(app)
    try:
        with one_line_warnings():
            result = command.main(args=argv, prog_name="mvtrack", standalone_mode=False)
    except _CLICK_ERROR as exc:
        if type(exc).__name__ == "NoArgsIsHelpError":  # bare `mvtrack`: the help, exit 0
            print(exc.format_message())  # type: ignore[attr-defined]
            return 0
        print(f"error: {_click_message(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return _signals.EXIT_INTERRUPTED
    except Exception as exc:
        if type(exc).__name__ == "Exit":
            return int(getattr(exc, "exit_code", 0))
        if type(exc).__name__ == "Abort":
            return _signals.EXIT_INTERRUPTED
        if isinstance(exc, (ValueError, OSError)):
            print(f"error: {exc}", file=sys.stderr)
            return 2
        raise
    return int(result) if isinstance(result, int) else 0


def _click_message(exc: Exception) -> str:
    """Click's message of a usage error, in one line; an unknown option names the command,
    suggests only a close match and points at the command's --help."""
    option = getattr(exc, "option_name", None)
    ctx = getattr(exc, "ctx", None)
    if type(exc).__name__ == "NoSuchOption" and option and ctx is not None:
        import difflib

        known = sorted(getattr(exc, "possibilities", None) or [])
        close = difflib.get_close_matches(option.lstrip("-"), [k.lstrip("-") for k in known],
                                          n=1, cutoff=0.75)
        hint = f" (did you mean --{close[0]}?)" if close else ""
        return (f"{ctx.command_path}: no such option {option}{hint}; "
                f"'{ctx.command_path} --help' lists the options")
    message = " ".join(exc.format_message().split())  # type: ignore[attr-defined]
    if message.startswith("No such command") and ctx is not None:
        message += f" '{ctx.command_path} --help' lists the commands."
    return message


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
