"""pydantic models of rigidid's files: the validation boundary.

Only :mod:`rigidid.io.files`, :mod:`rigidid.render` and the schema generator use
these models; the numerical core never sees them. The JSON Schemas in
``schemas/`` are generated from them (``python -m rigidid.schemas``).
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, field_validator, model_validator

__all__ = [
    "AXIS_DIRECTIONS",
    "BodyFile",
    "LayoutFile",
    "ModeRow",
    "MountSpec",
    "ReferencesFile",
    "ResultFile",
    "SensorSpec",
    "Units",
]

LengthUnit = Literal["m", "cm", "mm", "in", "ft"]
MassUnit = Literal["kg", "g", "t", "lb", "slug"]

AXIS_DIRECTIONS: dict[str, tuple[float, float, float]] = {
    "+x": (1.0, 0.0, 0.0),
    "-x": (-1.0, 0.0, 0.0),
    "+y": (0.0, 1.0, 0.0),
    "-y": (0.0, -1.0, 0.0),
    "+z": (0.0, 0.0, 1.0),
    "-z": (0.0, 0.0, -1.0),
}


def _finite(value: float) -> float:
    if not math.isfinite(value):
        raise ValueError("must be a finite number")
    return value


Finite = Annotated[float, AfterValidator(_finite)]
Vector3 = tuple[Finite, Finite, Finite]
Matrix3 = tuple[Vector3, Vector3, Vector3]
Matrix6 = list[list[float]]


def _axis_name(value: object) -> object:
    if isinstance(value, str):
        key = value.strip().lower()
        key = key if key[:1] in "+-" else "+" + key
        if key not in AXIS_DIRECTIONS:
            raise ValueError(f"unknown direction {value!r}: use +x, -x, +y, -y, +z, -z or a vector [x, y, z]")
        return key
    return value


def _nonzero(value: Vector3 | str) -> Vector3 | str:
    if not isinstance(value, str) and all(c == 0.0 for c in value):
        raise ValueError("direction is a zero vector")
    return value


def _text_id(value: object) -> object:
    if isinstance(value, int) and not isinstance(value, bool):
        return str(value)
    return value


class _Strict(BaseModel):
    # defer_build: a model's validator is built on first use, so that start-up
    # does not pay for models a command never touches.
    model_config = ConfigDict(extra="forbid", frozen=True, defer_build=True)


class Units(_Strict):
    """Units of every number in a file; time is always seconds."""

    length: LengthUnit
    mass: MassUnit


class SensorSpec(_Strict):
    """One single-axis sensor: where it is and along which axis it reads."""

    id: Annotated[str, BeforeValidator(_text_id), Field(min_length=1, description="unique sensor id (text)")]
    position: Vector3 = Field(description="location in the test's axes (length unit)")
    direction: Annotated[
        str | Vector3,
        BeforeValidator(_axis_name),
        AfterValidator(_nonzero),
        Field(description="+x, -x, +y, -y, +z, -z (bare x means +x), or a vector, normalised by the reader"),
    ]

    def unit_direction(self) -> tuple[float, float, float]:
        """The measuring axis as a unit vector."""
        if isinstance(self.direction, str):
            return AXIS_DIRECTIONS[self.direction]
        x, y, z = self.direction
        big = max(abs(x), abs(y), abs(z))  # scale first: [0, 0, 1e-200] and [1e300, 0, 0] normalise too
        x, y, z = x / big, y / big, z / big
        n = math.sqrt(x * x + y * y + z * z)
        return (x / n, y / n, z / n)


class TestBlock(_Strict):
    """``layout.json``'s optional ``test``: what was measured, when and by whom (shown in the report)."""

    __test__ = False  # not a pytest test class

    id: Annotated[str, Field(max_length=200, description="the test's id")] | None = None
    specimen: Annotated[str, Field(max_length=500, description="what was tested (part, serial number)")] | None = None
    date: Annotated[str, Field(max_length=100, description="date of the measurement, e.g. 2026-11-26")] | None = None
    operator: Annotated[str, Field(max_length=200, description="who measured")] | None = None
    notes: Annotated[str, Field(max_length=5000, description="anything else (set-up, conditions)")] | None = None


class SensorTolerances(_Strict):
    """Bounds of the sensors' errors (half-widths of rectangular distributions): a type-B budget.

    A field left out takes the default of :data:`rigidid.core.sensor_budget.DEFAULT_BOUNDS`.
    """

    sensitivity: Annotated[float, Field(ge=0.0, le=0.5, description="relative sensitivity error")] | None = None
    orientation_deg: Annotated[float, Field(ge=0.0, le=20.0, description="tilt per normal axis, deg")] | None = None
    transverse: Annotated[float, Field(ge=0.0, le=0.5, description="largest transverse sensitivity")] | None = None
    position: Annotated[float, Field(ge=0.0, description="position error per axis (length unit)")] | None = None


class AntiAliasSpec(_Strict):
    """An analog anti-alias filter as its data sheet states it (a linear-phase digital one is a delay)."""

    type: Literal["butterworth", "bessel"] = Field(description="the filter's type")
    order: Annotated[int, Field(ge=1, le=16, description="its order (number of poles)")]
    corner_hz: Annotated[float, AfterValidator(_finite), Field(gt=0.0, description="its -3 dB frequency (Hz)")]


class ChannelChainSpec(_Strict):
    """One channel's acquisition chain: AC coupling, anti-alias filter, delay (each optional)."""

    highpass_hz: (
        Annotated[float, AfterValidator(_finite), Field(ge=0.0, description="AC coupling's corner (Hz); 0: DC")] | None
    ) = None
    highpass_order: (
        Annotated[int, Field(ge=1, le=4, description="first-order high-pass sections in series (default 1)")] | None
    ) = None
    antialias: AntiAliasSpec | None = Field(default=None, description="the anti-alias filter (analog)")
    delay_s: (
        Annotated[float, AfterValidator(_finite), Field(ge=-1.0, le=1.0, description="the channel's delay (s)")] | None
    ) = None


class ChainSpec(ChannelChainSpec):
    """``layout.json``'s optional ``chain``: every channel's chain, and per-sensor entries overriding it field by field.

    The records' refit models it (FORMATS.md, "The acquisition chain").
    """

    sensors: dict[str, ChannelChainSpec] | None = Field(
        default=None, description="per sensor id: fields overriding the global ones for that channel"
    )


class ForceChannel(_Strict):
    """``layout.json``'s optional ``force``: the hammer's channel in the records and where it hits.

    With it (or ``--force COLUMN``), ``identify --records`` measures the mass (FORMATS.md,
    "The measured force").
    """

    column: Annotated[str, Field(min_length=1, description="the force channel's column name in the records")]
    position: Vector3 = Field(description="the drive point (length unit)")
    direction: Annotated[
        str | Vector3,
        BeforeValidator(_axis_name),
        AfterValidator(_nonzero),
        Field(description="the force's direction on the body: +x ... -z or a vector, normalised by the reader"),
    ]
    force_window: Annotated[float, Field(gt=0.0, description="force window: s after the pulse's start")] | None = None
    exponential_end: (
        Annotated[float, Field(gt=0.0, le=1.0, description="exponential window's value at the record's end (1: none)")]
        | None
    ) = None
    sensitivity: (
        Annotated[float, Field(ge=0.0, le=0.5, description="force sensor's relative sensitivity bound (type B)")] | None
    ) = None

    def unit_direction(self) -> tuple[float, float, float]:
        """The force's direction as a unit vector."""
        return SensorSpec(id="force", position=self.position, direction=self.direction).unit_direction()


class LayoutFile(_Strict):
    """``layout.json``: the sensors of a test and, optionally, the body's mass."""

    name: str | None = None
    units: Units
    mass: Annotated[float, Field(gt=0.0, description="mass of the body (mass unit)")] | None = None
    sensors: Annotated[list[SensorSpec], Field(min_length=1)]
    test: TestBlock | None = Field(default=None, description="test metadata for the report (all optional)")
    tolerances: SensorTolerances | None = Field(
        default=None, description="the sensors' error bounds, propagated into the records' intervals (type B)"
    )
    references: list[SensorSpec] | None = Field(
        default=None,
        min_length=1,
        description="FRF tests: the reference (force, hammer) points: id, position, force direction "
        "(as references.json has them)",
    )
    force: ForceChannel | None = Field(
        default=None, description="the hammer's force channel and drive point: identify --records measures the mass"
    )
    chain: ChainSpec | None = Field(
        default=None,
        description="the acquisition chain (AC coupling, anti-alias filter, delays): modelled in the refit",
    )

    @field_validator("mass")
    @classmethod
    def _mass_finite(cls, value: float | None) -> float | None:
        return None if value is None else _finite(value)

    @model_validator(mode="after")
    def _unique_ids(self) -> LayoutFile:
        seen: set[str] = set()
        for i, sensor in enumerate(self.sensors):
            if sensor.id in seen:
                raise ValueError(f"sensors.{i}.id: duplicate sensor id {sensor.id!r}")
            seen.add(sensor.id)
        for name in (self.chain.sensors or {}) if self.chain is not None else {}:
            if name not in seen:
                raise ValueError(f"chain.sensors.{name}: no sensor has this id")
        refs: set[str] = set()
        for i, ref in enumerate(self.references or []):
            if ref.id in refs:
                raise ValueError(f"references.{i}.id: duplicate reference id {ref.id!r}")
            refs.add(ref.id)
        return self


class ReferencesFile(_Strict):
    """``references.json``: the reference (force, hammer) points of an FRF test."""

    name: str | None = None
    units: Units | None = Field(default=None, description="if given, must equal the layout's units")
    references: Annotated[list[SensorSpec], Field(min_length=1, description="id, position, force direction")]

    @model_validator(mode="after")
    def _unique_ids(self) -> ReferencesFile:
        seen: set[str] = set()
        for i, ref in enumerate(self.references):
            if ref.id in seen:
                raise ValueError(f"references.{i}.id: duplicate reference id {ref.id!r}")
            seen.add(ref.id)
        return self


def _matrix3(value: object) -> object:
    """Accept three per-axis values as a diagonal matrix."""
    if isinstance(value, list | tuple) and len(value) == 3 and all(isinstance(v, int | float) for v in value):
        return [[float(value[0]), 0.0, 0.0], [0.0, float(value[1]), 0.0], [0.0, 0.0, float(value[2])]]
    return value


def _symmetric(value: Matrix3) -> Matrix3:
    scale = max(abs(v) for row in value for v in row) or 1.0
    for i in range(3):
        for j in range(i + 1, 3):
            if abs(value[i][j] - value[j][i]) > 1e-9 * scale:
                raise ValueError("matrix must be symmetric")
    return value


Matrix3Sym = Annotated[
    Matrix3, BeforeValidator(_matrix3, json_schema_input_type=Vector3 | Matrix3), AfterValidator(_symmetric)
]


class MountSpec(_Strict):
    """A massless elastic support acting at one point of the body."""

    position: Vector3 = Field(description="where the mount acts (length unit)")
    stiffness: Matrix3Sym = Field(description="3 per-axis values or a symmetric 3x3 matrix (mass/s^2)")
    damping: Matrix3Sym = Field(
        default=((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
        description="3 per-axis values or a symmetric 3x3 matrix (mass/s)",
    )


class BodyFile(_Strict):
    """``body.json``: a rigid body on mounts, the truth ``rigidid simulate`` starts from."""

    name: str | None = None
    units: Units
    mass: Annotated[float, Field(gt=0.0)]
    center_of_gravity: Vector3
    inertia_tensor: Matrix3Sym = Field(
        description="about the CG (mass length^2); off-diagonal entries are minus the products of inertia"
    )
    mounts: Annotated[list[MountSpec], Field(min_length=1)]

    @field_validator("mass")
    @classmethod
    def _mass_finite(cls, value: float) -> float:
        return _finite(value)


_AXES_COSINE = 1e-3
"""Largest |cosine| between two of a mount's axes read as orthogonal (axes typed to 4 digits pass)."""


def _unit_axes(value: Matrix3) -> Matrix3:
    """A mount's axes as unit rows (each scaled before its norm, so 1e-200 rows are fine), orthogonal."""
    rows: list[tuple[float, float, float]] = []
    for i, row in enumerate(value):
        big = max(abs(v) for v in row)
        if not big > 0.0:
            raise ValueError(f"axis {i + 1} is the zero vector")
        scaled = [v / big for v in row]
        norm = math.sqrt(sum(v * v for v in scaled))
        rows.append((scaled[0] / norm, scaled[1] / norm, scaled[2] / norm))
    for i in range(3):
        for j in range(i + 1, 3):
            cosine = sum(a * b for a, b in zip(rows[i], rows[j], strict=True))
            if abs(cosine) > _AXES_COSINE:
                raise ValueError(
                    f"axes {i + 1} and {j + 1} are not orthogonal (cosine {cosine:.3g}): "
                    "a mount's principal axes are three perpendicular directions"
                )
    return (rows[0], rows[1], rows[2])


class MountEntry(_Strict):
    """One mount of ``mounts.json``: where it acts and, optionally, its principal axes."""

    id: Annotated[str, BeforeValidator(_text_id)] | None = Field(default=None, description="the mount's name")
    position: Vector3 = Field(description="where the mount acts (length unit)")
    axes: Annotated[Matrix3, AfterValidator(_unit_axes)] | None = Field(
        default=None,
        description="its principal axes, one unit vector per row (compression first, then the two shears); "
        "default the layout's x, y, z",
    )
    stiffness: Matrix3Sym | None = Field(default=None, description="nominal rates (data sheet), mass/s^2")
    damping: Matrix3Sym | None = Field(default=None, description="nominal damping, mass/s")
    group: Annotated[str, BeforeValidator(_text_id)] | None = Field(
        default=None,
        description="mounts of one group are identical: they share their rates along their own axes "
        "(the mount model and the per-mount split fit one set per group)",
    )


class MountsFile(_Strict):
    """``mounts.json``: the supports of a body, for per-mount rates. A ``body.json`` is read as one too."""

    name: str | None = None
    units: Units
    mounts: Annotated[list[MountEntry], Field(min_length=1)]

    @model_validator(mode="after")
    def _unique_ids(self) -> MountsFile:
        seen: set[str] = set()
        for i, mount in enumerate(self.mounts):
            if mount.id is not None and mount.id in seen:
                raise ValueError(f"mounts.{i}.id: duplicate mount id {mount.id!r}")
            if mount.id is not None:
                seen.add(mount.id)
        return self


class ResultUnits(_Strict):
    """Units of the result; time is seconds."""

    length: LengthUnit
    mass: MassUnit
    time: Literal["s"] = "s"


class ModeDiagnostics(_Strict):
    """How one mode used was fitted."""

    mode: int
    frequency_hz: float
    damping_ratio: float
    rigid_fit_residual: float = Field(description="|psi - T T^+ psi| / |psi|: 0 for exact rigid-body motion")
    model_frequency_hz: float = Field(description="natural frequency of the identified model's matching mode")
    model_damping_ratio: float
    model_mac: float = Field(description="MAC between the measured shape and the identified model's shape")


class CandidateMode(_Strict):
    """A mode given, with how well its shape fits rigid-body motion."""

    mode: int
    rigid_fit_residual: float


class Diagnostics(_Strict):
    """Conditioning and goodness of fit."""

    layout_condition: float = Field(description="condition number of the dimensionless sensor transformation")
    layout_rank: int
    structure_residual: float = Field(description="relative asymmetry of (M/m) Q at the CG: 0 for an exact rigid body")
    inertia_observability: float = Field(
        description="0 (inertia not determined) to 1; typical rigs 0.1-0.3, below 0.03 a warning"
    )
    modes: list[ModeDiagnostics]
    candidate_modes: list[CandidateMode] | None = Field(
        default=None, description="every mode given, with its rigid-body fit residual, when the six were chosen"
    )
    warnings: list[str]


class EnergyDistribution(_Strict):
    """Modal kinetic-energy distribution (decoupling table): one row per mode used, rows sum to 1."""

    dof: list[str]
    principal_dof: list[str]
    modes: list[int]
    cg_axes: list[list[float]] = Field(description="shares in x, y, z, rx, ry, rz at the CG, layout axes")
    principal_axes: list[list[float]] = Field(description="shares with rotations about the principal axes")


class Interval(_Strict):
    """Monte Carlo estimate, standard deviation and 95 % interval of a quantity (scalars, vectors or matrices)."""

    estimate: Any
    std: Any
    ci95: Any


class StandardErrorMount(_Strict):
    """Standard errors of one mount's rates (units of the result's ``mounts``)."""

    id: str
    stiffness: list[float]
    damping: list[float | None]


class StandardErrorsResult(BaseModel):
    """Default linearised standard errors; quantity keys as the result's (``_per_mass`` without a mass)."""

    model_config = ConfigDict(extra="allow", frozen=True, defer_build=True)

    method: Literal["linearised"]
    weighted: bool = Field(description="whether the estimate is the noise-weighted one")
    noise: dict[str, float] = Field(description="the standard deviations propagated")
    misfit: float | None = Field(description="chi-square misfit of eq. (18) in noise units, null if not computed")
    misfit_dof: int
    inflation: float = Field(description="sqrt(max(1, misfit / misfit_dof)); every standard error is scaled by it")
    failed: int
    center_of_gravity: list[float]
    principal_axes_deg: list[float]
    mounts: list[StandardErrorMount] | None = None
    torque_roll_axis_deg: float | None = None


class UncertaintyResult(BaseModel):
    """Uncertainty intervals (``identify --uncertainty N``); quantity keys end in ``_per_mass`` without a mass."""

    model_config = ConfigDict(extra="allow", frozen=True, defer_build=True)

    center_of_gravity: Interval
    per_mass: bool
    draws: int
    failed: int
    implausible: int
    seed: int | None
    noise: dict[str, float]


class RecordSpreadResult(BaseModel):
    """Data-driven intervals from interleaved segments of the records (``--resample K``)."""

    model_config = ConfigDict(extra="allow", frozen=True, defer_build=True)

    method: str
    segments: int
    used: int
    center_of_gravity: Interval


class ForceUnitsResult(_Strict):
    """Stiffness and damping in force units: ``*_force = factor * *_matrix``."""

    force: Literal["N", "kN", "lbf"]
    factor: float = Field(description="kg per mass unit * m per length unit / N per force unit")
    stiffness: dict[str, str] = Field(description="units of the translation, coupling and rotation blocks")
    damping: dict[str, str] = Field(description="units of the translation, coupling and rotation blocks")


class SensorCorrectionEntry(_Strict):
    """One sensor's errors estimated with the body by ``--estimate-sensors`` (issue 23)."""

    gain: float = Field(description="relative gain error (0.01: the sensor reads 1 % high)")
    gain_std: float = Field(description="its posterior standard deviation")
    tilt_rad: list[float] = Field(
        description="its axis turned towards the two unit normals e1 (normal to the axis and to x, or to y "
        "for an axis near x) and e2 = axis x e1 (radians)"
    )
    tilt_std_rad: list[float] = Field(description="their posterior standard deviations (radians)")
    determined: list[bool] = Field(
        description="whether the records determine the gain and each tilt (else the tolerance's prior holds)"
    )
    shift: list[float] | None = Field(
        default=None,
        description="its position shifted along x, y, z (layout length; absent in results written before it)",
    )
    shift_std: list[float] | None = Field(default=None, description="their posterior standard deviations")
    shift_determined: list[bool] | None = Field(
        default=None,
        description="whether the records determine each shift (never the one along the sensor's own axis; "
        "else the tolerance's prior holds)",
    )


class AcCouplingEntry(_Strict):
    """The score test for an AC coupling the layout's chain does not state (issue 23)."""

    corner_hz: float = Field(
        description="the first-order high-pass corner common to the channels whose transient e^(-2 pi f t) per "
        "channel and impact best explains the refit's residual (Hz)"
    )
    corner_std_hz: float | None = Field(
        description="its standard error from the statistic's profile (null: the corner is at the edge of the "
        "rates tried)"
    )
    statistic: float = Field(description="chi-square score statistic of those transients at that corner")
    dof: int = Field(description="its degrees of freedom (channels times impacts)")
    p_value: float = Field(description="its p-value, Bonferroni-corrected over the 30 corners tried")
    false_alarm_rate: float = Field(
        description="the rate the test is judged at (1e-9): below it, and with interior true, the test flags"
    )
    interior: bool = Field(
        description="whether the statistic peaks inside the corners tried (half the longest decay's inverse to half "
        "the lowest rigid-body frequency); false: not taken for a coupling, whatever the p-value"
    )
    modelled: bool = Field(
        description="whether the refit reported models a high-pass at corner_hz on every channel (by default when "
        "the test flags)"
    )


class SensorTestEntry(_Strict):
    """The score test of the sensors as stated at the plain refit's minimum (issue 23)."""

    statistic: float = Field(
        description="chi-square statistic of the CG's and inertia's move the sensors' correction would make, "
        "over its noise covariance"
    )
    dof: int = Field(description="its degrees of freedom (0: the stated tolerances let nothing move)")
    p_value: float = Field(description="probability of a statistic at least this large with exact sensors")
    false_alarm_rate: float = Field(description="the rate the test was run at: below it, the test flags")
    sensors_estimated: bool = Field(
        description="whether the sensors' errors were estimated with the body (sensor_corrections): by default "
        "when the test flags (through the chain when one is modelled; not without a pre-trigger); always with "
        "--estimate-sensors, never with "
        "--no-estimate-sensors"
    )
    correction_misfit_p_value: float | None = Field(
        default=None,
        description="when the sensors were estimated (or tried by default): the misfit test's p-value of the last "
        "corrected refit against the noise plus what the correction leaves of the tolerances; below "
        "correction_false_alarm_rate the default keeps the plain refit (sensors_estimated false)",
    )
    correction_false_alarm_rate: float | None = Field(
        default=None,
        description="the rate correction_misfit_p_value is judged at (0.001; absent in results written before it, "
        "when it was false_alarm_rate)",
    )


class RecordBoundResult(BaseModel):
    """Cramér-Rao intervals of the output-error refinement on the records (``--refine``, the default)."""

    model_config = ConfigDict(extra="allow", frozen=True, defer_build=True)

    method: str
    normalised_cost: float
    noise_from: Literal["pretrigger", "residual"]
    residuals: int
    variance_from: Literal["sandwich"] | None = Field(
        default=None,
        description="how the std were estimated: sandwich = robust covariance from the fit's residual per impact "
        "and channel, the decimation filter's correlation and the remaining Gauss-Newton step",
    )
    evaluations: int | None = Field(default=None, description="residual evaluations of the refit's optimiser")
    converged: bool | None = Field(
        default=None,
        description="whether the refit met its convergence test (Gauss-Newton decrement below 0.05 residual "
        "variances, or stalled at the J, K, C > 0 boundary) rather than stopping at its evaluation budget",
    )
    center_of_gravity: Interval
    misfit_ratio: float | None = Field(
        default=None,
        description="the refit's residual variance over the pre-trigger's noise variance (about 1 at a good fit; "
        "inverse-variance weighted geometric mean over impacts and channels)",
    )
    misfit_p_value: float | None = Field(
        default=None,
        description="one-sided p-value of the misfit test (F-test of each impact's and channel's residual against "
        "its pre-trigger, pooled): the refit is accepted when it is at least false_alarm_rate",
    )
    false_alarm_rate: float | None = Field(
        default=None, description="the acceptance test's false-alarm rate (fraction of right models rejected)"
    )
    misfit_expected: float | None = Field(
        default=None,
        description="the misfit ratio a right model is expected to leave: 1 plus the part the stated sensor "
        "tolerances explain (their errors' signatures less what the fit absorbs, on average)",
    )
    sensor_budget: dict[str, dict[str, list[float] | list[list[float]]]] | None = Field(
        default=None,
        description="standard deviation of center_of_gravity and inertia_tensor from each source: noise (the "
        "refit's bound) and the sensors' sensitivity, orientation, transverse sensitivity and position "
        "tolerances (type B); std is their root sum of squares",
    )
    tolerances: dict[str, float] | None = Field(
        default=None, description="the sensor error bounds the budget used (position in the layout's length unit)"
    )
    channel_delays: dict[str, dict[str, float]] | None = Field(
        default=None,
        description="--estimate-delays: per channel id, delay_s (its delay beyond the layout's chain, relative to "
        "the first channel fitted) and std_s (its standard error)",
    )
    mains_hum_hz: list[float] | None = Field(
        default=None, description="mains hum frequencies found in the records and modelled in the refit (Hz)"
    )
    sensor_corrections: dict[str, SensorCorrectionEntry] | None = Field(
        default=None,
        description="per sensor id, its errors estimated with the body (gains, tilts, position shifts)",
    )
    sensor_test: SensorTestEntry | None = Field(
        default=None,
        description="with sensor tolerances: the test of the sensors as stated, and whether they were estimated",
    )
    ac_coupling: AcCouplingEntry | None = Field(
        default=None,
        description="without a high-pass in the layout's chain: the test for an AC coupling nobody stated, and "
        "whether the refit models it",
    )


class ForceMassResult(_Strict):
    """The mass measured by the records' force channel: the per-mass body fitted to the H1 FRFs."""

    estimate: float = Field(description="the mass (mass unit)")
    std: float = Field(description="its standard error: noise and the gains' tolerances in quadrature")
    ci95: tuple[float, float] = Field(description="estimate -/+ 1.96 std")
    budget: dict[str, float] = Field(
        description="std per source: noise (the responses'), force_noise, sensitivity (the sensors' gains), "
        "force_sensitivity, body (the per-mass body's standard errors)"
    )
    band_hz: tuple[float, float] = Field(description="the FFT lines fitted (Hz)")
    lines: int = Field(description="how many lines")
    relative_residual: float = Field(description="RMS misfit of the fit relative to the FRFs (weighted)")
    misfit_noise_units: float = Field(
        description="RMS misfit over the FRFs' noise (from third differences along frequency); about 1 at a good "
        "fit; the responses' part of std is multiplied by max(1, misfit)"
    )
    coherence: float = Field(description="mean H1 coherence over the band and the sensors")
    estimator: str = Field(
        "H1",
        description="how 1/m was fitted: errors-in-variables (the force's samples in their window and the "
        "responses' spectra in one likelihood; the default) or H1 (the H1 FRFs by weighted least squares)",
    )


class ScaledModesResult(_Strict):
    """The body from six rigid-body modes scaled by the force (unity modal A): absolute units, at the CG."""

    mass: float
    center_of_gravity: Vector3
    inertia_tensor: Matrix3
    stiffness_matrix: Matrix6 = Field(description="mass/s^2 (rotations in radians), DOF x, y, z, rx, ry, rz")
    damping_matrix: Matrix6 = Field(description="mass/s")


class ResultFile(_Strict):
    """The result JSON of ``rigidid identify`` (FORMATS.md); matrices are lists of rows, DOF x, y, z, rx, ry, rz."""

    rigidid_version: str
    method: Literal["structured", "paper", "mounts"]
    units: ResultUnits
    mass: float | None
    center_of_gravity: list[float]
    inertia_per_mass: list[list[float]]
    inertia_tensor: list[list[float]] | None
    principal_moments: list[float] | None
    principal_moments_per_mass: list[float]
    principal_axes: list[list[float]]
    stiffness_per_mass: Matrix6
    stiffness_matrix: Matrix6 | None
    damping_per_mass: Matrix6
    damping_matrix: Matrix6 | None
    modes_used: list[int]
    modes_selected: Literal["all", "given", "automatic"] = Field(
        description="all: exactly six given; given: --modes; automatic: the six most rigid-body-like"
    )
    energy_distribution: EnergyDistribution
    diagnostics: Diagnostics
    uncertainty: UncertaintyResult | None = None
    standard_errors: StandardErrorsResult | None = Field(
        default=None, description="default linearised standard errors of the structured route's figures"
    )
    uncertainty_records: RecordSpreadResult | None = None
    uncertainty_records_crb: RecordBoundResult | None = Field(
        default=None, description="with --records and --refine: Cramér-Rao bound at the output-error fit"
    )
    modal_estimation: dict[str, Any] | None = Field(
        default=None, description="with --records: estimator, impacts found, modes and stabilisation diagram"
    )
    force_units: ForceUnitsResult | None = Field(
        default=None, description="unit strings and factor of stiffness_force and damping_force (null without mass)"
    )
    stiffness_force: Matrix6 | None = Field(
        default=None, description="stiffness_matrix in force units (force_units.stiffness), null without mass"
    )
    damping_force: Matrix6 | None = Field(
        default=None, description="damping_matrix in force units (force_units.damping), null without mass"
    )
    quantity_units: dict[str, str] | None = Field(
        default=None, description="the unit of every numeric key of the result (a text such as 'lb in^2')"
    )
    mounts: MountsResult | None = Field(default=None, description="with --mounts: per-mount rates")
    mount_model: MountModelResult | None = Field(
        default=None, description="with --method mounts: the mount model's fit against the free 6x6 matrices"
    )
    torque_roll_axis: TorqueRollAxisResult | None = Field(
        default=None, description="with --torque-axis: the rotation under a pure torque"
    )
    mass_measured: float | None = Field(
        default=None,
        description="with six modal_a scaled modes (modes --frf): the mass from the scaled modes; with a force "
        "channel (identify --records): the mass the force measured",
    )
    mass_source: Literal["force"] | None = Field(
        default=None, description="with a force channel: 'force', the mass used is the measured one"
    )
    force_mass: ForceMassResult | None = Field(
        default=None, description="with a force channel (identify --records): the mass measured and how"
    )
    mass_given: float | None = Field(default=None, description="with mass_measured: the mass given, else null")
    mass_difference: float | None = Field(default=None, description="mass_measured - mass_given, else null")
    mass_difference_relative: float | None = Field(
        default=None, description="mass_measured / mass_given - 1, else null"
    )
    scaled_modes: ScaledModesResult | None = Field(
        default=None, description="with six modal_a scaled modes: the body from them in absolute units"
    )


class MountResult(_Strict):
    """One mount's identified rates along its axes."""

    id: str
    position: Vector3
    axes: Matrix3 = Field(description="principal axes, one unit vector per row")
    stiffness: Vector3 = Field(description="rates along the axes (mounts.units.stiffness)")
    damping: Vector3 = Field(description="damping along the axes (mounts.units.damping)")
    nominal_stiffness: Vector3 | None = Field(default=None, description="the file's nominal rates along the axes")
    group: str | None = Field(default=None, description="the mount's group of identical mounts (mounts.json)")


class MountsResult(_Strict):
    """Per-mount rates fitted to the identified stiffness and damping."""

    units: dict[str, str] = Field(description="units of stiffness and damping")
    mounts: list[MountResult]
    stiffness_residual: float = Field(description="|K - K_mounts| / |K|: 0 when the mounts explain K")
    damping_residual: float
    unknowns: int
    rank: int = Field(description="rates the mount layout determines (unique when equal to unknowns)")
    unique: bool
    statement: str


class MountModelResult(_Strict):
    """How well the mount model explains the modes, against the free 6x6 stiffness and damping."""

    residual: float = Field(description="RMS eigenproblem residual (lambda^2 M + lambda C + K) phi, dimensionless")
    parameters: int
    equations: int
    aic: float = Field(description="Akaike's criterion N ln(RSS/N) + 2 P")
    free_residual: float | None = Field(description="the same for the free route (null with five modes)")
    free_parameters: int
    free_aic: float | None
    adequate: bool | None = Field(description="the mount model's AIC is not worse than the free route's")
    f_statistic: float | None = Field(
        default=None,
        description="F test of the mount model against any linear rigid-body model on noise-weighted output residuals",
    )
    f_dof: tuple[int, int] | None = Field(default=None, description="its degrees of freedom (numerator, denominator)")
    p_value: float | None = Field(default=None, description="chance of an F this large when the mount model is right")
    significance: float | None = Field(default=None, description="p_value below this flags the mount model")
    f_test_adequate: bool | None = Field(
        default=None,
        description="the F test's verdict, p_value >= significance (null when no test could be made); "
        "prefer it to adequate",
    )
    noise: dict[str, float] | None = Field(default=None, description="noise levels weighting the output residuals")
    groups: int | None = Field(default=None, description="distinct mounts fitted (mounts of a group count once)")


class TorqueRollAxisResult(_Strict):
    """The axis about which the body turns under a pure torque."""

    torque_axis: Vector3
    direction: Vector3 = Field(description="unit direction of J^-1 t")
    angle_to_torque_deg: float
    angle_to_principal_deg: Vector3 = Field(description="to each principal axis, ascending moments")


class ModeRow(_Strict):
    """One row of ``modes.csv``: one sensor's value in one mode."""

    mode: Annotated[int, Field(gt=0)]
    frequency_hz: Annotated[Finite, Field(gt=0.0)]
    damping_ratio: Annotated[Finite, Field(ge=0.0, lt=1.0)]
    sensor: Annotated[str, Field(min_length=1)]
    real: Finite
    imag: Finite = 0.0
