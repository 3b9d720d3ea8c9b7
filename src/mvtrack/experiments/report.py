"""The result of an experiment, and how it is written: ``NAME.json``, ``NAME.md``, PNG plots."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mvtrack.io.atomic import atomic_path, write_json, write_text


@dataclass
class Report:
    """What an experiment found, ready to be written.

    Attributes
    ----------
    name : str
        Experiment name (``NAME`` in the file names).
    title : str
        One-line title for the Markdown page (which paper figure or table it reproduces).
    figures : dict
        JSON-serialisable figures: ours, and the paper's reported values beside them.
    columns : list of str
        Header of the Markdown table, e.g. ``["quantity", "paper", "ours"]``.
    rows : list of list
        Rows of the Markdown table.
    notes : str
        Markdown paragraphs after the table: setup, what matches, what does not.
    plots : dict
        File stem -> matplotlib Figure, saved as ``NAME_<stem>.png``.
    variants : dict
        Settings other than the specification's that the experiment also runs: name -> the
        reason it is run. The headline figures always use the specification's settings; the
        variants are listed with their reasons under the table and in the JSON
        (``variant_reasons``).
    """

    name: str
    title: str
    figures: dict[str, Any]
    columns: list[str]
    rows: list[list[Any]]
    notes: str = ""
    plots: dict[str, Any] = field(default_factory=dict)
    variants: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.variants:
            self.figures = {**self.figures, "variant_reasons": dict(self.variants)}

    def markdown(self) -> str:
        """The Markdown page: title, table, variants with their reasons, notes, plots."""
        lines = [f"# {self.title}", "", "| " + " | ".join(self.columns) + " |"]
        lines.append("|" + "---|" * len(self.columns))
        lines += ["| " + " | ".join(_fmt(v) for v in row) + " |" for row in self.rows]
        if self.variants:
            lines += ["", "Headline figures use the specification's settings. Variants:", ""]
            lines += [f"- *{name}*: {why}" for name, why in self.variants.items()]
        if self.notes:
            lines += ["", self.notes.strip()]
        if self.plots:
            lines += [""] + [f"![{stem}]({self.name}_{stem}.png)" for stem in self.plots]
        return "\n".join(lines) + "\n"


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def write_report(report: Report, out: str | Path) -> list[Path]:
    """Write ``NAME.json``, ``NAME.md`` and ``NAME_<plot>.png`` into ``out``; return the paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = [write_json(out / f"{report.name}.json", report.figures)]
    for stem, fig in report.plots.items():
        dest = out / f"{report.name}_{stem}.png"
        with atomic_path(dest) as tmp:
            fig.savefig(tmp, dpi=110, bbox_inches="tight")
        plt.close(fig)
        paths.append(dest)
    paths.append(write_text(out / f"{report.name}.md", report.markdown()))
    return paths
