"""``rigidid identify``: CG, inertia, stiffness and damping from modes, records or FRFs."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rigidid.cli.common import (
    add_mounts,
    check_force_unit,
    check_options,
    check_outputs,
    identify_files,
    noise_overrides,
    parse_modes,
    parse_units,
    reported,
    stage_tables,
    write_csv,
    write_json,
)
from rigidid.cli.options import (
    AngleNoise,
    Band,
    CsvDir,
    DampingNoise,
    Decimate,
    Draws,
    EstimateDelays,
    EstimateHighpass,
    EstimateSensors,
    ForceColumn,
    ForceUnit,
    FrequencyNoise,
    FrfOut,
    FrfPath,
    Geometry,
    IdMethod,
    Inputs,
    JsonPath,
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
from rigidid.errors import InputError

if TYPE_CHECKING:
    from rigidid.core.timedomain import ModalEstimate
    from rigidid.results import IdentifyResult


def identify(
    layout: Annotated[
        Path, typer.Argument(metavar="LAYOUT", help="Sensor layout (layout.json), or a UFF file.", show_default=False)
    ],
    inputs: Inputs = None,
    records: RecordsFlag = False,
    mass: Mass = None,
    modes_used: ModesUsed = None,
    method: IdMethod = None,
    json_path: JsonPath = None,
    uff: Annotated[
        Path | None,
        typer.Option(metavar="FILE", help="Also write the identified modes and geometry as a UFF file (15, 55, 82)."),
    ] = None,
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
    csv: CsvDir = None,
    frf: FrfPath = None,
    references: ReferencesPath = None,
    mounts: MountsPath = None,
    torque_axis: TorqueAxis = None,
    refine: Refine = True,
    estimate_sensors: EstimateSensors = None,
    estimate_highpass: EstimateHighpass = None,
    force: ForceColumn = None,
    frf_out: FrfOut = None,
    estimate_delays: EstimateDelays = False,
) -> None:
    """Identify CG, inertia tensor, stiffness and damping from a layout and its modes (or impact records)."""
    with reported():
        if method in FRF_METHODS or frf is not None or _uff_of_frfs(layout, inputs, records, units, geometry):
            if records:
                raise InputError("give --records or --frf, not both", source="--frf")
            check_options(mass=mass, band=band)
            check_outputs({"--json": json_path})
            _identify_massline(
                layout, frf, references, mass=mass, band=band, method=method or "auto", json_path=json_path,
                modes=inputs, modes_used=modes_used, units=units, geometry=geometry,
            )  # fmt: skip
            return
        method = method or "structured"
        force_unit = check_force_unit(force_unit)

        check_outputs({"--json": json_path, "--uff": uff, "--frf-out": frf_out}, {"--csv": csv})
        if frf_out is not None and not records:
            raise InputError("--frf-out needs impact records with a force channel (--records)", source="--frf-out")
        if estimate_delays and not (records and refine):
            raise InputError("needs impact records and the refit (--records, without --no-refine)",
                             source="--estimate-delays")  # fmt: skip
        if estimate_highpass is not None and not (records and refine):
            flag = "--estimate-highpass" if estimate_highpass else "--no-estimate-highpass"
            raise InputError("needs impact records and the refit (--records, without --no-refine)", source=flag)
        noise = noise_overrides(
            frequency=frequency_noise, damping=damping_noise, shape=shape_noise, position=position_noise,
            angle_deg=angle_noise,
        )  # fmt: skip
        modal = {"method": modal_method, "n_modes": n_modes, "band": band, "max_order": max_order, "decimate": decimate}
        run = identify_files(
            layout, inputs, records, units, modal, mass=mass, modes_used=modes_used, method=method, draws=uncertainty,
            noise=noise, seed=seed, resample=resample, geometry=geometry, mounts=mounts, refine=refine,
            estimate_sensors=estimate_sensors, estimate_highpass=estimate_highpass, **_force_options(force, frf_out),
            **({"estimate_delays": True} if estimate_delays else {}),
        )  # fmt: skip
        result, estimate = run.result, run.estimate
        result = add_mounts(result, mounts, torque_axis)
        _publish(result, estimate, json_path=json_path, uff=uff, csv=csv, force_unit=force_unit)


def _force_options(column: str | None, frf_out: Path | None) -> dict[str, Any]:
    """``force=ForceOptions(...)`` for the API when ``--force`` or ``--frf-out`` is given, else nothing."""
    if column is None and frf_out is None:
        return {}
    from rigidid.api.force import ForceOptions

    return {"force": ForceOptions(column=column, frf_out=frf_out)}


def _publish(
    result: IdentifyResult,
    estimate: ModalEstimate | None,
    *,
    json_path: str | None,
    uff: Path | None,
    csv: Path | None,
    force_unit: str | None,
) -> None:
    """Every output of ``identify`` or none: the result JSON, the UFF, the CSV matrices, the tables."""
    from rigidid.io.atomic import OutputSet
    from rigidid.jsonout import result_to_dict

    with OutputSet():  # every output or none
        if json_path is not None:
            out = result_to_dict(result, force_unit)
            if estimate is not None:
                from rigidid.jsonout import estimate_to_dict

                out["modal_estimation"] = estimate_to_dict(estimate)
            write_json(json_path, out)
        if uff is not None:
            from rigidid.io.uff import write_uff

            write_uff(uff, result.positions, result.directions, result.sensor_ids, result.identification, result.units)
        if csv is not None:
            write_csv(csv, result, force_unit)
        if json_path != "-":
            from rigidid.render import estimate_tables, result_tables

            tables = [estimate_tables(estimate)] if estimate is not None else []
            stage_tables(*tables, result_tables(result, force_unit))


FRF_METHODS = ("auto", "massline", "residues")
"""``--method`` values of the FRF routes (``auto`` is the default when FRFs are given)."""


def _uff_of_frfs(
    layout: Path, inputs: list[Path] | None, records: bool, units: str | None, geometry: Path | None
) -> bool:
    """Whether LAYOUT is a UFF file of FRFs given alone (``rigidid identify test.uff``)."""
    from rigidid.api.load import UFF_SUFFIXES, load_uff

    if records or inputs or layout.suffix.lower() not in UFF_SUFFIXES:
        return False
    from rigidid.io.uff import uff_function_types

    types = uff_function_types(layout) if layout.is_file() else None  # the headers: the file is read once, later
    if types is not None:
        return 4 in types
    return load_uff(layout, units=parse_units(units, layout), geometry=geometry).frf is not None


def _identify_massline(
    layout: Path,
    frf: Path | None,
    references: Path | None,
    *,
    mass: float | None,
    band: tuple[float, float] | None,
    method: str,
    json_path: str | None,
    modes: list[Path] | None = None,
    modes_used: str | None = None,
    units: str | None = None,
    geometry: Path | None = None,
) -> None:
    """``identify --frf`` (``--method auto|massline|residues``): mass, CG and inertia from FRFs (rigidid.api.frf)."""
    from rigidid.api import frf as api_frf
    from rigidid.jsonout import massline_to_dict

    if method not in FRF_METHODS:
        raise InputError(
            f"FRFs are identified with --method {', '.join(FRF_METHODS)}, not {method!r}", source="--method"
        )
    modes_file = None
    if method == "residues" and modes:
        if len(modes) != 1:
            raise InputError("--method residues takes one modes.csv (its rigid-body poles)", source="MODES")
        modes_file = modes[0]
    parsed = parse_modes(modes_used) if method == "residues" else None
    labels = tuple(parsed) if parsed is not None else None
    if modes and method != "residues":
        raise InputError("a modes file goes with --method residues (its rigid-body poles)", source="MODES")
    result = api_frf.identify_massline(
        layout, frf, references, mass=mass, band=band, modes=modes_file, modes_used=labels, method=method,
        units=parse_units(units, layout), geometry=geometry,
    )  # fmt: skip
    from rigidid.io.atomic import OutputSet

    with OutputSet():  # standard output first, then the file: every output or none
        if json_path is not None:
            write_json(json_path, massline_to_dict(result))
        if json_path != "-":
            from rigidid.render import massline_tables

            stage_tables(massline_tables(result))
