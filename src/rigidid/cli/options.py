"""Option and argument types shared by the commands (``Annotated`` typer options), and the map from the API's
parameter names to the options that set them (:data:`FLAGS`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

UFF_SUFFIXES = (".uff", ".unv")


UNCERTAINTY_PANEL = "Uncertainty"


RECORDS_PANEL = "Time records"


Mass = Annotated[
    float | None, typer.Option(help="Mass of the body in the layout's mass unit (overrides the layout).", metavar="M")
]


ModesUsed = Annotated[
    str | None,
    typer.Option(
        "--modes", help="The six rigid-body mode labels, e.g. 1,2,3,5,6,7.", metavar="LABELS", show_default=False
    ),
]


IdMethod = Annotated[
    str | None,
    typer.Option(
        help="structured (default, robust), paper (the paper's eqs. 25-26 and 36-40), mounts (CG, inertia and "
        "per-mount rates fitted together; needs --mounts); from FRFs: auto (default: every route the data allow, "
        "one chosen, cross-checked), massline, or residues (scaled modes, poles fitted or from MODES).",
        metavar="METHOD",
    ),
]


FrfPath = Annotated[
    Path | None,
    typer.Option(
        "--frf",
        help="FRFs (accelerance, CSV or UFF); references from --references, the layout's `references` or the "
        "UFF headers.",
        metavar="FILE",
        show_default=False,
    ),
]


ReferencesPath = Annotated[
    Path | None,
    typer.Option(help="references.json: force points and directions of the FRFs.", metavar="FILE", show_default=False),
]


JsonPath = Annotated[
    str | None,
    typer.Option("--json", help="Also write the result as JSON to PATH ('-': standard output only).", metavar="PATH"),
]


Draws = Annotated[
    int,
    typer.Option(
        help="Monte Carlo draws for uncertainty intervals (0: none).", metavar="N", rich_help_panel=UNCERTAINTY_PANEL
    ),
]


FrequencyNoise = Annotated[
    float | None,
    typer.Option(
        help="Relative std of natural frequencies \\[default: 0.001].", metavar="X", rich_help_panel=UNCERTAINTY_PANEL
    ),
]


DampingNoise = Annotated[
    float | None,
    typer.Option(
        help="Relative std of damping ratios \\[default: 0.05].", metavar="X", rich_help_panel=UNCERTAINTY_PANEL
    ),
]


ShapeNoise = Annotated[
    float | None,
    typer.Option(
        help="Std of shape values relative to each mode's RMS \\[default: from the rigid-body fit with more than "
        "six sensors, else 0.01].",
        metavar="X",
        rich_help_panel=UNCERTAINTY_PANEL,
    ),
]


PositionNoise = Annotated[
    float | None,
    typer.Option(
        help="Std of sensor positions (length unit) \\[default: 0].", metavar="X", rich_help_panel=UNCERTAINTY_PANEL
    ),
]


AngleNoise = Annotated[
    float | None,
    typer.Option(
        help="Std of sensor directions (degrees) \\[default: 0].", metavar="X", rich_help_panel=UNCERTAINTY_PANEL
    ),
]


Seed = Annotated[int, typer.Option(help="Seed of the random draws.", metavar="N")]


Resample = Annotated[
    int,
    typer.Option(
        help="With --records: also re-identify on K interleaved segments of the records for a data-driven interval "
        "(sample rate / K must stay above twice the highest mode; 8 is a good choice).",
        metavar="K",
        rich_help_panel=UNCERTAINTY_PANEL,
    ),
]


Inputs = Annotated[
    list[Path] | None,
    typer.Argument(
        metavar="MODES|RECORDS",
        help="modes.csv; or, with --records, one records.csv per impact. Not needed when LAYOUT is a UFF file "
        "with modes (55) or records (58).",
        show_default=False,
    ),
]


RecordsFlag = Annotated[
    bool,
    typer.Option(
        "--records",
        help="The inputs are impact records: estimate the modes first.",
        metavar="",
        rich_help_panel=RECORDS_PANEL,
    ),
]


ModalMethod = Annotated[
    str | None,
    typer.Option(
        help="Modal estimator for records: era or ar \\[default: era].", metavar="METHOD", rich_help_panel=RECORDS_PANEL
    ),
]


Band = Annotated[
    tuple[float, float] | None,
    typer.Option(help="Frequency band of the modes (Hz).", metavar="FMIN FMAX", rich_help_panel=RECORDS_PANEL),
]


MaxOrder = Annotated[
    int | None, typer.Option(help="Highest model order of the sweep.", metavar="N", rich_help_panel=RECORDS_PANEL)
]


Decimate = Annotated[
    int | None,
    typer.Option(help="Decimation factor \\[default: from the spectrum].", metavar="N", rich_help_panel=RECORDS_PANEL),
]


NModes = Annotated[
    int,
    typer.Option(help="Modes to estimate from records (more than 6 when elastic modes share the band).", metavar="N"),
]


ForceUnit = Annotated[
    str | None,
    typer.Option(
        help="Force unit of stiffness and damping: N, kN or lbf \\[default: N for kg, g, t; lbf for lb, slug].",
        metavar="UNIT",
    ),
]


CsvDir = Annotated[
    Path | None,
    typer.Option(
        "--csv", help="Also write each result matrix as a CSV file (for spreadsheets) into DIR.", metavar="DIR"
    ),
]


Refine = Annotated[
    bool,
    typer.Option(
        "--refine/--no-refine",
        help="With --records: refine the body by an output-error fit to the records, with Cramér-Rao intervals.",
        metavar="",
        rich_help_panel=RECORDS_PANEL,
    ),
]


EstimateDelays = Annotated[
    bool,
    typer.Option(
        "--estimate-delays",
        help="With --records: the refit also fits each channel's delay (relative to the first) and reports it.",
        rich_help_panel=RECORDS_PANEL,
    ),
]


EstimateSensors = Annotated[
    bool | None,
    typer.Option(
        "--estimate-sensors/--no-estimate-sensors",
        help="With --records and more than six channels: estimate each sensor's gain, axis and position errors "
        "with the body in the refit (the layout's tolerances as their prior); a sensor beyond 3x its tolerance "
        "is named. Default: only when the records show sensor errors that move the body (the sensor test, "
        "false-alarm rate 1 %), through the chain when one is modelled, not without a pre-trigger; "
        "--no-estimate-sensors: "
        "never.",
        show_default=False,
        rich_help_panel=RECORDS_PANEL,
    ),
]

EstimateHighpass = Annotated[
    bool | None,
    typer.Option(
        "--estimate-highpass/--no-estimate-highpass",
        help="With --records and no highpass_hz in the layout's chain: model an AC coupling (one first-order "
        "high-pass on every channel) at the corner the refit's residual shows. Default: only when its score test "
        "finds one (false-alarm rate 1e-9); --no-estimate-highpass: tested and reported, never modelled.",
        show_default=False,
        rich_help_panel=RECORDS_PANEL,
    ),
]

Units = Annotated[
    str | None,
    typer.Option(help="Units of a UFF file without dataset 164, as LENGTH,MASS (e.g. in,lb).", metavar="L,M"),
]


MountsPath = Annotated[
    Path | None,
    typer.Option(
        "--mounts",
        help="mounts.json (or a body.json): mount positions and axes; adds per-mount rates fitted to K and C.",
        metavar="FILE",
        show_default=False,
    ),
]


TorqueAxis = Annotated[
    str | None,
    typer.Option(
        help="Axis of a pure torque (x, y, z or X,Y,Z; for an engine the crankshaft): adds the torque roll axis.",
        metavar="AXIS",
        show_default=False,
    ),
]


Geometry = Annotated[
    Path | None,
    typer.Option(
        help="A UFF file with the nodes (15/2411), coordinate systems (18/2420) and units (164) of a UFF input "
        "that lacks them.",
        metavar="FILE",
    ),
]


ForceColumn = Annotated[
    str | None,
    typer.Option(
        "--force",
        help="The records' force (hammer) column: measure the mass with it (the drive point from layout.json's "
        "'force' block; the layout's block alone also does).",
        metavar="COLUMN",
    ),
]
FrfOut = Annotated[
    Path | None,
    typer.Option(
        help="With a force channel: write the H1 FRFs (with coherence) here, .csv or .uff/.unv, and "
        "<stem>.references.json beside them, for identify --frf / modes --frf.",
        metavar="FILE",
    ),
]


FLAGS = {
    "modes_used": "--modes",
    "uncertainty": "--uncertainty",
    "draws": "--uncertainty",
    "segments": "--resample",
    "add": "--add",
    "impacts": "--impact",
    "band": "--band",
    "max_order": "--max-order",
    "units": "--units",
    "frf_format": "--frf-format",
    "modal_method": "--modal-method",
    "geometry": "--geometry",
    "rtol": "--rtol",
    "sigma": "--sigma",
    "records": "--records",
    "refine": "--no-refine",
    "n_modes": "--n-modes",
    "decimate": "--decimate",
    "records_format": "--records-format",
    "frequency_noise": "--add-frequency-noise",
    "damping_noise": "--add-damping-noise",
    "mass": "--mass",
    "pretrigger": "--pretrigger",
    "force": "--force",
    "estimate_sensors": "--estimate-sensors",
    "estimate_highpass": "--estimate-highpass",
    "estimate_delays": "--estimate-delays",
    "sample_rate": "--sample-rate",
    "duration": "--duration",
    "record_noise": "--record-noise",
}
"""API parameter names, as the API's errors name them, and the options that set them."""

# simulate's record and FRF outputs
RecordsOut = Annotated[
    Path | None,
    typer.Option(
        "--write-records",
        help="Also write impulse-response records (record-<k>.csv) into DIR.",
        metavar="DIR",
        rich_help_panel=RECORDS_PANEL,
    ),
]
Impacts = Annotated[
    list[str] | None,
    typer.Option(
        help="Impact as X,Y,Z:DX,DY,DZ (position, force direction); repeat for several records "
        "\\[default: two impacts at the first sensors].",
        metavar="X,Y,Z:DX,DY,DZ",
        rich_help_panel=RECORDS_PANEL,
    ),
]
SampleRate = Annotated[float, typer.Option(help="Samples per second.", metavar="HZ", rich_help_panel=RECORDS_PANEL)]
Duration = Annotated[float, typer.Option(help="Free decay per record (s).", metavar="S", rich_help_panel=RECORDS_PANEL)]
Pretrigger = Annotated[
    float, typer.Option(help="Record before the impact (s).", metavar="S", rich_help_panel=RECORDS_PANEL)
]
RecordNoise = Annotated[
    float,
    typer.Option(
        "--add-record-noise",
        help="Add noise relative to each channel's RMS.",
        metavar="X",
        rich_help_panel=RECORDS_PANEL,
    ),
]
FrfFormat = Annotated[
    str | None,
    typer.Option(
        "--frf-format",
        help="Format of --write-frf: csv, uff (binary 58b) or uff-ascii (58) \\[default: from the suffix].",
        metavar="FORMAT",
        show_default=False,
    ),
]
