"""The forms of a :class:`~rigidid.compare.Comparison`: a rich table and a JUnit XML report.

Both return values; the command line decides where they go.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rigidid.compare import Comparison, EntryCheck, FigureCheck

__all__ = ["comparison_junit", "comparison_table", "figure_verdict"]


def _num(x: float | None, digits: int = 6) -> str:
    if x is None:
        return "-"
    return f"{x:.{digits}g}"


def figure_verdict(figure: FigureCheck, sigma: float) -> str:
    """One line: how the worst entry of `figure` stands against its allowance."""
    worst = figure.worst(sigma)
    if worst.value is None:
        return f"{figure.name} {worst.label}: absent from the result" + (f" ({figure.note})" if figure.note else "")
    d = worst.difference
    assert d is not None
    parts = [f"difference {_num(d)} {worst.unit}".rstrip(), f"tolerance {_num(worst.tolerance)} (rtol {figure.rtol:g})"]
    if worst.sigma is not None:
        parts.append(f"{abs(d) / worst.sigma:.2g} combined standard errors" if worst.sigma > 0 else "standard error 0")
    state = "within" if figure.passed(sigma) else "outside"
    return f"{figure.name} {worst.label}: {state}: " + ", ".join(parts)


def _status(entry: EntryCheck, sigma: float) -> str:
    if entry.value is None:
        return "[red]missing[/red]"
    if entry.within_tolerance:
        return "[green]ok[/green]"
    if entry.within_sigma(sigma):
        return f"[green]ok ({sigma:g} SE)[/green]"
    return "[red]REGRESSION[/red]"


def comparison_table(comparison: Comparison) -> Any:
    """A rich table, one row per figure, showing its worst entry against its allowance."""
    from rich.markup import escape
    from rich.table import Table

    k = comparison.sigma
    title = f"{comparison.result} against {comparison.reference}"
    table = Table(title=title, title_justify="left", show_edge=False)
    table.add_column("figure", overflow="fold", min_width=10)
    table.add_column("worst entry", overflow="fold", min_width=8)
    table.add_column("verdict", no_wrap=True)
    for head in ("difference", "tolerance", "|diff|/SE"):
        table.add_column(head, justify="right", no_wrap=True)
    for head in ("result", "reference"):
        table.add_column(head, justify="right", overflow="fold")
    for figure in comparison.figures:
        if not figure.entries:
            continue
        worst = figure.worst(k)
        d = worst.difference
        ratio = "-" if worst.sigma is None or d is None or worst.sigma == 0 else f"{abs(d) / worst.sigma:.2g}"
        table.add_row(
            escape(figure.name),
            escape(f"{worst.label} ({_unit_word(worst.unit)})" if worst.unit else worst.label),
            _status(worst, k),
            _num(d, 4),
            _num(worst.tolerance, 4),
            ratio,
            _num(worst.value, 4),
            _num(worst.reference, 4),
        )
    return table


def _unit_word(unit: str) -> str:
    """A unit as one word (``kg·mm^2``), so a wrapped table never breaks inside it."""
    return unit.replace(" ", "\u00b7")


def comparison_junit(comparison: Comparison, suite: str = "rigidid compare") -> str:
    """A JUnit XML report: one test case per figure, a ``<failure>`` for each regression.

    The class name is the reference's name, so that a CI system groups the cases of
    one test (one reference) together.
    """
    import xml.etree.ElementTree as ET

    k = comparison.sigma
    cases = [f for f in comparison.figures if f.entries]
    failed = [f for f in cases if not f.passed(k)]
    root = ET.Element("testsuites", tests=str(len(cases)), failures=str(len(failed)))
    node = ET.SubElement(root, "testsuite", name=suite, tests=str(len(cases)), failures=str(len(failed)), errors="0")
    props = ET.SubElement(node, "properties")
    for name, value in (("result", comparison.result), ("reference", comparison.reference), ("sigma", f"{k:g}")):
        ET.SubElement(props, "property", name=name, value=value)
    for figure in cases:
        case = ET.SubElement(node, "testcase", classname=comparison.reference, name=figure.name)
        lines = [
            f"{e.label}: result {_num(e.value)} reference {_num(e.reference)} difference {_num(e.difference)} "
            f"tolerance {_num(e.tolerance)} se {_num(e.sigma)} {e.unit}".rstrip()
            for e in figure.entries
            if not e.passed(k)
        ]
        if lines:
            failure = ET.SubElement(case, "failure", message=figure_verdict(figure, k), type="regression")
            failure.text = "\n".join(lines)
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
