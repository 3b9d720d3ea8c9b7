"""Assemble ``docs/benchmarks.md`` from the summary and the per-area tables in ``docs/bench/``.

Each benchmark script writes (or its run is pasted into) one fragment ``docs/bench/<area>.md``
with the exact command and the conditions of the run; ``docs/bench/summary.md`` holds the
headline figures against the targets. This script only concatenates them, in a fixed order,
so ``docs/benchmarks.md`` always shows the latest of each::

    python benchmarks/assemble_docs.py
"""

from __future__ import annotations

import argparse
from pathlib import Path

from mvtrack.io.atomic import write_text

ROOT = Path(__file__).resolve().parents[1]
#: fragments in reading order: the summary, the development benchmark (the frame-rate sweep,
#: its rules and defaults), then from the filters up to whole videos
ORDER = (
    "summary", "framerate", "heldout", "rules", "defaults", "joint", "dropout", "filters",
    "association",
    "tracker", "numpy-floor", "mot15", "tud", "pipeline", "frontend", "vehicles", "analytics",
    "structured", "sim", "batch",
)
TITLE = "# Benchmarks\n"


def assemble(bench_dir: Path) -> str:
    """The text of ``docs/benchmarks.md``: the title and every fragment of ``ORDER`` that exists,
    then any other fragment in ``bench_dir`` (sorted), so none is forgotten."""
    names = [n for n in ORDER if (bench_dir / f"{n}.md").exists()]
    names += sorted(p.stem for p in bench_dir.glob("*.md") if p.stem not in ORDER)
    parts = [TITLE]
    for name in names:
        text = (bench_dir / f"{name}.md").read_text(encoding="utf-8").strip()
        parts.append(f"<!-- from docs/bench/{name}.md -->\n{text}\n")
    return "\n".join(parts)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bench-dir", type=Path, default=ROOT / "docs" / "bench")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "benchmarks.md")
    args = parser.parse_args()
    write_text(args.out, assemble(args.bench_dir))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
