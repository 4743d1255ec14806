"""``rigidid compare``: a result JSON against a reference, figure by figure; exit 1 on a regression."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from rigidid.cli.common import EXIT_IDENTIFICATION, check_outputs, make_console, reported


def compare(
    result: Annotated[
        Path, typer.Argument(metavar="RESULT", help="The result JSON to check (identify --json).", show_default=False)
    ],
    reference: Annotated[
        Path, typer.Argument(metavar="REFERENCE", help="The reference result JSON.", show_default=False)
    ],
    rtol: Annotated[
        str,
        typer.Option(
            metavar="RTOL",
            help="Relative tolerance: a number, or per figure, e.g. 1e-3,stiffness=0.05 (figures: mass, "
            "center_of_gravity, inertia, principal_moments, stiffness, damping, mounts).",
        ),
    ] = "1e-6",
    sigma: Annotated[
        float,
        typer.Option(
            metavar="K", help="Also pass an entry within K combined standard errors of the two results (0: off)."
        ),
    ] = 0.0,
    junit: Annotated[
        Path | None, typer.Option(metavar="FILE", help="Also write a JUnit XML report (one case per figure).")
    ] = None,
) -> None:
    """Compare a result with a reference figure by figure; exit 1 on a regression, 2 on bad input."""
    with reported():
        from rigidid import api
        from rigidid.compare import parse_tolerances
        from rigidid.compare_render import comparison_junit, comparison_table, figure_verdict
        from rigidid.io.atomic import write_text_atomic

        check_outputs({"--junit": junit})
        comparison = api.compare(result, reference, rtol=parse_tolerances(rtol), sigma=sigma)
        make_console().print(comparison_table(comparison))
        if junit is not None:
            write_text_atomic(junit, comparison_junit(comparison))
            sys.stderr.write(f"rigidid: wrote {junit}\n")
    for figure in comparison.regressions:
        sys.stderr.write(f"rigidid: regression: {figure_verdict(figure, comparison.sigma)}\n")
    if not comparison.passed:
        raise typer.Exit(EXIT_IDENTIFICATION)
