"""The command line: unknown commands and options end in one line and a non-zero exit."""

from __future__ import annotations

import subprocess
import sys


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "mvtrack", *args], capture_output=True, text=True, check=False
    )


def test_unknown_command_is_one_line_error() -> None:
    proc = _run("no-such-command")
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:"), proc.stderr
    assert "Traceback" not in proc.stderr


def test_unknown_experiment_is_one_line_error(tmp_path) -> None:
    proc = _run("experiment", "no-such-experiment", "--out", str(tmp_path))
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0 and "no-such-experiment" in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_unknown_option_is_one_line_error() -> None:
    proc = _run("experiment", "predictors", "--bogus")
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0 and "--bogus" in proc.stderr


def test_version_prints_the_package_version() -> None:
    import mvtrack

    proc = _run("--version")
    assert proc.returncode == 0 and proc.stdout.strip() == f"mvtrack {mvtrack.__version__}"
