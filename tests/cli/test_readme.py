"""The README's examples as a new user runs them: the Python snippet gives the results of the
command line's defaults, and every command of the README names options that exist."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from mvtrack.cli import main

README = Path(__file__).resolve().parents[2] / "README.md"


def _python_snippet() -> str:
    text = README.read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) == 1, "the README has one Python snippet"
    return blocks[0]


def test_the_python_snippet_runs_the_command_lines_defaults(tmp_path: Path, monkeypatch,
                                                            capsys) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "crowd", "--n", "40", "--frames", "60", "--detections",
                 "--out", "out/crowd"]) == 0
    assert main(["track-detections", "out/crowd/det.txt", "--out", "out/crowd/res",
                 "--fps", "30"]) == 0
    namespace: dict[str, object] = {}
    exec(compile(_python_snippet(), "README.md", "exec"), namespace)
    ours = Path("out/crowd/results.txt").read_text()
    assert ours and ours == Path("out/crowd/res/det.txt").read_text()
    log = namespace["log"]
    assert len(log) == 60  # the online loop saw every frame  # type: ignore[arg-type]


def _readme_commands() -> list[list[str]]:
    text = README.read_text(encoding="utf-8")
    commands = []
    for block in re.findall(r"```bash\n(.*?)```", text, flags=re.S):
        for line in block.splitlines():
            line = line.split("  #")[0].strip()
            if line.startswith("mvtrack "):
                commands.append(shlex.split(line)[1:])
    return commands


@pytest.mark.parametrize("args", _readme_commands(), ids=" ".join)
def test_every_readme_command_parses(args: list[str], capsys) -> None:
    """Each command of the README with --help appended: the command and every option it
    names exist (a renamed option fails here, not in a user's terminal)."""
    assert main([*args, "--help"]) == 0, capsys.readouterr().err
