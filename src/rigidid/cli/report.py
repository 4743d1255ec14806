"""``rigidid report``: the HTML report (and PNG figures) of an identification."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rigidid.cli.common import (
    add_mounts,
    check_force_unit,
    check_options,
    check_outputs,
    identify_files,
    noise_overrides,
    refuse_unused,
    reported,
)
from rigidid.cli.options import (
    AngleNoise,
    Band,
    DampingNoise,
    Decimate,
    Draws,
    ForceUnit,
    FrequencyNoise,
    FrfPath,
    Geometry,
    IdMethod,
    Inputs,
    Mass,
    MaxOrder,
    ModalMethod,
    ModesUsed,
    MountsPath,
    NModes,
    PositionNoise,
    RecordsFlag,
    ReferencesPath,
    Refine,
    Resample,
    Seed,
    ShapeNoise,
    TorqueAxis,
    Units,
)

if TYPE_CHECKING:
    from rigidid.models import BodyFile
    from rigidid.results import IdentifyResult, TestRun


def report(
    layout: Annotated[
        Path, typer.Argument(metavar="LAYOUT", help="Sensor layout (layout.json), or a UFF file.", show_default=False)
    ],
    inputs: Inputs = None,
    output: Annotated[Path, typer.Option("-o", "--output", metavar="FILE", help="The HTML report to write.")] = Path(
        "report.html"
    ),
    png: Annotated[
        Path | None, typer.Option(metavar="DIR", help="Also write the figures as PNG files into DIR.")
    ] = None,
    body: Annotated[
        Path | None, typer.Option(metavar="FILE", help="body.json whose mounts (and their stiffness) to draw.")
    ] = None,
    title: Annotated[
        str | None,
        typer.Option(metavar="TEXT", help="Title of the report \\[default: the layout's name, else 'rigidid report']."),
    ] = None,
    records: RecordsFlag = False,
    mass: Mass = None,
    modes_used: ModesUsed = None,
    method: IdMethod = "structured",
    uncertainty: Draws = 0,
    frequency_noise: FrequencyNoise = None,
    damping_noise: DampingNoise = None,
    shape_noise: ShapeNoise = None,
    position_noise: PositionNoise = None,
    angle_noise: AngleNoise = None,
    seed: Seed = 0,
    resample: Resample = 0,
    modal_method: ModalMethod = None,
    n_modes: NModes = 6,
    band: Band = None,
    max_order: MaxOrder = None,
    decimate: Decimate = None,
    units: Units = None,
    geometry: Geometry = None,
    force_unit: ForceUnit = None,
    refine: Refine = True,
    mounts: MountsPath = None,
    torque_axis: TorqueAxis = None,
    frf: FrfPath = None,
    references: ReferencesPath = None,
) -> None:
    """Identify, then write one self-contained HTML report with tables and pictures.

    With --frf (or a UFF file of FRFs as LAYOUT) the report is of the FRF routes: every route tried, the mass line
    and the scaled modes side by side (--method chooses the one tabled first, auto as identify does), the FRFs with
    the fits and bands, the mass line, the stabilisation diagram. References come from --references, the layout's
    list or the UFF headers, as for identify.
    """
    with reported():
        from rigidid.io.files import load_body
        from rigidid.units import check_same_units

        force_unit = check_force_unit(force_unit)
        if frf is not None or method in ("massline", "residues", "auto") or _uff_of_frfs(layout, inputs, records):
            _refuse_for_frf(
                records=records, uncertainty=uncertainty > 0, body=body is not None,
                mounts=mounts is not None, torque_axis=torque_axis is not None, resample=resample > 0,
                modal_method=modal_method is not None, decimate=decimate is not None, max_order=max_order is not None,
                frequency_noise=frequency_noise is not None, damping_noise=damping_noise is not None,
                shape_noise=shape_noise is not None, position_noise=position_noise is not None,
                angle_noise=angle_noise is not None,
            )  # fmt: skip
            _write_frf_report(
                layout, frf, references, inputs, output=output, png=png, method=method or "auto", mass=mass,
                band=band, modes_used=modes_used, title=title, force_unit=force_unit, units=units, geometry=geometry,
            )  # fmt: skip
            return
        check_outputs({"--output": output}, {"--png": png})
        noise = noise_overrides(
            frequency=frequency_noise, damping=damping_noise, shape=shape_noise, position=position_noise,
            angle_deg=angle_noise,
        )  # fmt: skip
        modal = {"method": modal_method, "n_modes": n_modes, "band": band, "max_order": max_order, "decimate": decimate}
        run = identify_files(
            layout, inputs, records, units, modal, mass=mass, modes_used=modes_used, method=method or "structured",
            draws=uncertainty, noise=noise, seed=seed, resample=resample, geometry=geometry, spectrum=True,
            refine=refine, mounts=mounts,
        )  # fmt: skip
        result = add_mounts(run.result, mounts, torque_axis)
        spec = None if body is None else load_body(body)
        if spec is not None:
            check_same_units(spec.units, result.units, source=str(body))
        named = [str(p) for p in (layout, *(inputs or []))]
        _write_report(run, result, spec, output=output, png=png, title=title, inputs=named, force_unit=force_unit)


def _write_report(
    run: TestRun,
    result: IdentifyResult,
    spec: BodyFile | None,
    *,
    output: Path,
    png: Path | None,
    title: str | None,
    inputs: list[str],
    force_unit: str | None,
) -> None:
    """The HTML report (and the PNG figures) of `result`, every file or none."""
    from rigidid import api
    from rigidid.io.atomic import OutputSet, write_text_atomic
    from rigidid.progress import terminal_progress
    from rigidid.reporting import FIGURE_NAMES

    diagram = None if run.estimate is None else run.estimate.diagram
    with OutputSet() as outs:  # every output or none; the figures drawn once for the page and the PNG files
        folder = None if png is None else outs.folder(png, option="--png")
        with terminal_progress() as progress:
            text = api.report(
                result, stabilisation=diagram, title=title, inputs=inputs,
                force_unit=force_unit, body=spec, records=run.records, progress=progress,
                spectrum=run.spectrum, png=folder,
            )  # fmt: skip
        write_text_atomic(output, text)
    sys.stderr.write(f"rigidid: wrote {output}\n")
    if png is not None:
        drawn = [name for name in FIGURE_NAMES if name != "stabilisation" or diagram is not None]
        sys.stderr.write(f"rigidid: wrote {len(drawn)} figures to {png}\n")


def _uff_of_frfs(layout: Path, inputs: list[Path] | None, records: bool) -> bool:
    """Whether LAYOUT is a UFF file of FRFs given alone (``rigidid report test.uff``), from its headers only."""
    from rigidid.api.load import UFF_SUFFIXES
    from rigidid.io.uff import uff_function_types

    if records or inputs or layout.suffix.lower() not in UFF_SUFFIXES or not layout.is_file():
        return False
    return 4 in (uff_function_types(layout) or ())


def _write_frf_report(
    layout: Path,
    frf: Path | None,
    references: Path | None,
    inputs: list[Path] | None,
    *,
    output: Path,
    png: Path | None,
    method: str,
    mass: float | None,
    band: tuple[float, float] | None,
    modes_used: str | None,
    title: str | None,
    force_unit: str | None,
    units: str | None,
    geometry: Path | None,
) -> None:
    """``report --frf``: the FRF routes side by side (rigidid.api.reports.frf_report), with --png the figures."""
    from rigidid import api
    from rigidid.cli.common import parse_modes, parse_units
    from rigidid.errors import InputError
    from rigidid.frf_report import FRF_FIGURE_NAMES
    from rigidid.io.atomic import OutputSet, write_text_atomic
    from rigidid.progress import terminal_progress

    check_options(mass=mass, band=band)
    check_outputs({"--output": output}, {"--png": png})
    if method not in ("massline", "residues", "structured", "auto"):
        raise InputError(
            f"FRFs are reported with --method auto, massline or residues, not {method!r}", source="--method"
        )
    if len(inputs or []) > 1:
        raise InputError("a report of FRFs takes one modes.csv (its rigid-body poles)", source="MODES")
    modes = inputs[0] if inputs else None
    labels = parse_modes(modes_used) if modes_used is not None else None
    named = [str(p) for p in (layout, frf, references, *(inputs or [])) if p is not None]
    with OutputSet() as outs:  # the page and the figures, or nothing
        folder = None if png is None else outs.folder(png, option="--png")
        with terminal_progress() as progress:
            text = api.frf_report(
                layout, frf, references, method="auto" if method == "structured" else method, mass=mass,
                band=band, modes=modes, modes_used=None if labels is None else tuple(labels), title=title,
                inputs=named, force_unit=force_unit, progress=progress, png=folder,
                units=parse_units(units, layout), geometry=geometry,
            )  # fmt: skip
        write_text_atomic(output, text)
    sys.stderr.write(f"rigidid: wrote {output}\n")
    if png is not None:
        drawn = sum((png / f"{name}.png").is_file() for name in FRF_FIGURE_NAMES)
        sys.stderr.write(f"rigidid: wrote {drawn} figures to {png}\n")


def _refuse_for_frf(**given: bool) -> None:
    """Refuse the options of the modes and records routes in a report of FRFs (name -> whether given)."""
    refuse_unused(
        "applies to the modes and records routes, not to a report of FRFs (--frf)",
        {"--" + name.replace("_", "-"): was for name, was in given.items()},
    )
