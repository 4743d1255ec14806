"""The result types of the API (frozen dataclasses): what a workflow returns and what the presentation
(JSON, tables, report) reads. Below the API and the presentation; imports neither."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray

from rigidid.core.identify import Identification
from rigidid.io.files import ModeTable
from rigidid.models import LayoutFile

if TYPE_CHECKING:
    from rigidid.core.frfmodes import FrfModes, ScaledBody
    from rigidid.core.linearised import StandardErrors
    from rigidid.core.massline import MassLine
    from rigidid.core.mounts import MountModel, MountModelPrediction, MountRates, TorqueRollAxis
    from rigidid.core.noise import NoiseLevels
    from rigidid.core.plan import LayoutReport, Prediction, ReferenceReport, SensorPlan
    from rigidid.core.record_spread import RecordSpread
    from rigidid.core.timedomain import ModalEstimate
    from rigidid.core.timedomain.force import ForceMass
    from rigidid.core.timedomain.refine import RecordBound
    from rigidid.core.uncertainty import Uncertainty
    from rigidid.io.files import ModeTable


Selection = Literal["all", "given", "automatic"]


@dataclass(frozen=True)
class IdentifyResult:
    """An identification with the context needed to report it.

    Attributes
    ----------
    identification : Identification
        The numbers (CG, inertia, stiffness, damping, diagnostics).
    units : dict
        ``{"length": ..., "mass": ...}`` of the layout.
    sensor_ids : tuple of str
    positions, directions : ndarray, shape (p, 3)
        The layout (directions as unit vectors).
    modes_used : tuple of int
        Mode labels used, in the order of the identification's modes.
    selection : {"all", "given", "automatic"}
        How the six modes were chosen.
    candidate_residuals : dict or None
        Rigid-body fit residual of every mode given, when chosen automatically.
    poles : ndarray of complex, shape (6,)
        Poles of the modes used (rad/s).
    shapes : ndarray of complex, shape (p, 6)
        Their shapes at the sensors.
    uncertainty : Uncertainty or None
        Monte Carlo intervals, when asked for.
    record_spread : RecordSpread or None
        Data-driven intervals from interleaved segments of the records
        (:func:`with_record_spread`).
    layout_name : str or None
        The layout's ``name``.
    test : TestInfo or None
        The layout's ``test`` block (id, specimen, date, operator, notes), for the report.
    mounts : Mounts or None
        Per-mount rates fitted to the stiffness and damping (:func:`with_mounts`).
    torque_roll_axis : TorqueRollAxis or None
        The rotation under a torque about a given axis (:func:`with_mounts`).
    mount_model : MountModelFit or None
        With ``method="mounts"``: the mount model's fit against the free route.
    record_bound : RecordBound or None
        Cramér-Rao intervals of the output-error refinement on the records
        (:func:`with_refinement`); set when the refinement replaced the
        structured answer.
    scaled : ScaledBody or None
        When the six modes used are scaled to unity modal A (``modes.csv``
        column ``scaling`` ``modal_a``, written by ``rigidid modes --frf``):
        the mass, CG, inertia, stiffness and damping in absolute units from the
        scaled modes (:func:`rigidid.core.frfmodes.body_from_scaled_shapes`).
    standard_errors : StandardErrors or None
        Linearised standard errors of the structured route's answer, computed
        by default (:func:`rigidid.core.linearised.standard_errors`).
    torque_roll_axis_std_deg : float or None
        Angular standard error of the torque roll axis (:func:`rigidid.api.with_mounts`).
    force_mass : ForceMass or None
        The mass measured by the records' force channel (:func:`rigidid.api.force.measure_mass`);
        then ``identification.mass`` is it.
    mass_given : float or None
        With `force_mass`: the layout's or the ``mass`` option's mass, reported beside it.
    """

    identification: Identification
    units: dict[str, str]
    sensor_ids: tuple[str, ...]
    positions: NDArray[np.float64]
    directions: NDArray[np.float64]
    modes_used: tuple[int, ...]
    selection: Selection
    candidate_residuals: dict[int, float] | None = None
    poles: NDArray[np.complex128] | None = None
    shapes: NDArray[np.complex128] | None = None
    uncertainty: Uncertainty | None = None
    record_spread: RecordSpread | None = None
    record_bound: RecordBound | None = None
    layout_name: str | None = None
    mounts: Mounts | None = None
    torque_roll_axis: TorqueRollAxis | None = None
    mount_model: MountModelFit | None = None
    scaled: ScaledBody | None = None
    standard_errors: StandardErrors | None = None
    torque_roll_axis_std_deg: float | None = None
    test: TestInfo | None = None
    force_mass: ForceMass | None = None
    mass_given: float | None = None


@dataclass(frozen=True)
class TestInfo:
    """What was measured, when and by whom: the layout's optional ``test`` block (each field optional).

    Attributes
    ----------
    id, specimen, date, operator, notes : str or None
        The test's id, the part tested, the date of the measurement, who measured, anything else.
    """

    __test__ = False  # not a pytest test class

    id: str | None = None
    specimen: str | None = None
    date: str | None = None
    operator: str | None = None
    notes: str | None = None

    @classmethod
    def from_layout(cls, layout: LayoutFile) -> TestInfo | None:
        """The layout's ``test`` block, or None without one."""
        block = layout.test
        if block is None:
            return None
        return cls(block.id, block.specimen, block.date, block.operator, block.notes)


@dataclass(frozen=True)
class MountModelFit:
    """How well the mount model explains the modes, against the free 6x6 matrices.

    Attributes
    ----------
    model : MountModel
        The fit (rates per mass, residual, parameter count).
    free_residual : float or None
        The same eigenproblem residual for the free route (``method="structured"``),
        when six modes allow it.
    free_parameters : int
        Unknowns of the free route: CG, ``J/m``, ``K/m`` and ``C/m`` (51).
    """

    model: MountModel
    residual: float
    free_residual: float | None
    free_parameters: int = 51
    noise: NoiseLevels | None = None

    def _aic(self, residual: float, parameters: int) -> float:
        n = self.model.equations
        return float(n * np.log(max(residual**2, 1e-30)) + 2 * parameters)

    @property
    def aic(self) -> float:
        """Akaike's criterion ``N ln(RSS / N) + 2 P`` of the mount model (RSS floored at 1e-30 N)."""
        return self._aic(self.residual, self.model.parameters)

    @property
    def free_aic(self) -> float | None:
        """Akaike's criterion of the free route on the same equations."""
        return None if self.free_residual is None else self._aic(self.free_residual, self.free_parameters)

    @property
    def adequate(self) -> bool | None:
        """True when the mount model explains the modes as well as the free matrices (lower or equal AIC)."""
        free = self.free_aic
        return None if free is None else bool(self.aic <= free)

    @property
    def verdict(self) -> bool | None:
        """Does the mount model explain the modes: the F test's (:attr:`MountModel.adequate`) when it
        could be made, else :attr:`adequate` (AIC, which flags correct noisy models too often)."""
        return self.adequate if self.model.adequate is None else self.model.adequate


@dataclass(frozen=True)
class Mounts:
    """Per-mount rates of an identification, with the mounts' ids and positions.

    Attributes
    ----------
    ids : tuple of str
        Mount names (``"1"``, ``"2"``... when the file gives none).
    positions : ndarray, shape (n, 3)
        Where they act (length).
    rates : MountRates
        Rates along each mount's axes (force units come from the presentation).
    nominal : ndarray, shape (n, 3) or None
        The file's nominal rates along the same axes, when every mount gives them.
    stiffness_std, damping_std : ndarray, shape (n, 3) or None
        Linearised standard errors of the rates (units of `rates`, scaled by the
        mass when known), when the identification has standard errors.
    """

    ids: tuple[str, ...]
    positions: NDArray[np.float64]
    rates: MountRates
    nominal: NDArray[np.float64] | None = None
    groups: tuple[str | None, ...] | None = None
    stiffness_std: NDArray[np.float64] | None = None
    damping_std: NDArray[np.float64] | None = None


@dataclass(frozen=True)
class PlanResult:
    """A sensor layout checked before the test, with predictions when a body estimate is given.

    Attributes
    ----------
    units : dict
        The layout's units.
    report : LayoutReport
        Rank, condition and findings in words.
    prediction : Prediction or None
        Predicted standard deviations of CG and inertia (needs a body).
    suggestions : SensorPlan or None
        The sensors to add, best first (needs a body and ``add > 0``).
    references : ReferenceReport or None
        Whether the reference (hammer) points of an FRF test excite all six
        rigid-body motions (needs ``references``).
    sensor_budget : dict of str to dict of str to ndarray, or None
        Predicted standard deviation per source (needs a body): ``"noise"`` (the
        prediction's draws), then the sensors' tolerances
        (:data:`rigidid.core.sensor_budget.SOURCES`, propagated as ``identify``
        propagates them), then ``"combined"`` (all in quadrature); each with
        ``"center_of_gravity"`` (3,), ``"inertia_tensor"`` (3, 3) and
        ``"stiffness_diagonal"`` (6,), absolute units.
    tolerances : dict of str to float or None
        The bounds the budget used (the layout's ``tolerances``, defaults for the rest).
    records_budget : dict of str to dict of str to ndarray, or None
        With a records test planned: the sensor budget ``identify --records`` will report, the
        refit's own (:func:`rigidid.api.planning.predicted_records_budget`), per source and
        ``"sensors"`` (the four in quadrature), keys as `sensor_budget`'s.
    records_test : dict or None
        The records test it was predicted for (impacts, rate, duration, the refit's decimation).
    """

    units: dict[str, str]
    report: LayoutReport
    prediction: Prediction | None = None
    suggestions: SensorPlan | None = None
    references: ReferenceReport | None = None
    mount_split: tuple[int, int, str] | None = None
    mount_prediction: MountModelPrediction | None = None
    sensor_budget: dict[str, dict[str, NDArray[np.float64]]] | None = None
    tolerances: dict[str, float] | None = None
    records_budget: dict[str, dict[str, NDArray[np.float64]]] | None = None
    records_test: dict[str, Any] | None = None


@dataclass(frozen=True)
class TestData:
    """What a test file set provides: the layout, and modes and/or time records.

    Attributes
    ----------
    layout : LayoutFile
    modes : ModeTable or None
    records : list of (ndarray, float)
        Per impact: samples x sensors (layout order) and the sample interval (s).
    record_names : list of str
        Where each record came from.
    frf : FrfData or None
        A UFF file of FRFs (datasets 58, function type 4): the FRFs, sensors in
        layout order, references in the order of ``layout.references``.
    """

    layout: LayoutFile
    modes: ModeTable | None = None
    records: list[tuple[NDArray[np.float64], float]] = field(default_factory=list)
    record_names: list[str] = field(default_factory=list)
    frf: FrfData | None = None


@dataclass(frozen=True)
class Arrays:
    """A layout and its modes as the numerical core takes them.

    Attributes
    ----------
    sensor_ids : tuple of str
    positions, directions : ndarray, shape (p, 3)
        Sensor locations (length) and unit measuring axes.
    labels : tuple of int
        Mode labels.
    poles : ndarray of complex, shape (n,)
        One pole per mode (rad/s).
    shapes : ndarray of complex, shape (p, n)
    mass : float or None
    """

    sensor_ids: tuple[str, ...]
    positions: NDArray[np.float64]
    directions: NDArray[np.float64]
    labels: tuple[int, ...]
    poles: NDArray[np.complex128]
    shapes: NDArray[np.complex128]
    mass: float | None


@dataclass(frozen=True)
class FrfData:
    """FRFs of a test with their sensors and references.

    Attributes
    ----------
    frequencies : ndarray, shape (f,)
        Hz.
    frf : ndarray of complex, shape (p, q, f)
        Accelerance (1 / mass unit).
    sensor_ids, reference_ids : tuple of str
    """

    frequencies: NDArray[np.float64]
    frf: NDArray[np.complex128]
    sensor_ids: tuple[str, ...]
    reference_ids: tuple[str, ...]


@dataclass(frozen=True)
class MassLineResult:
    """``identify --method massline``: the mass line and how it compares with a given mass.

    Attributes
    ----------
    massline : rigidid.core.massline.MassLine
    units : dict
        ``{"length": ..., "mass": ...}`` of the layout.
    mass_given : float or None
        The mass of the layout or of the ``mass`` parameter, if any.
    reason : str
        Why this route was used.
    route : str
        ``"massline"`` or ``"residues"`` (scaled modes).
    scaled : rigidid.core.frfmodes.ScaledBody or None
        Route residues: the body from the six scaled rigid-body modes, with the
        stiffness and damping in absolute units.
    routes : tuple of RouteAnswer
        ``--method auto``: every route tried, in order, with its answer or why
        it does not apply (empty for a route asked by name).
    fitted : rigidid.core.frfmodes.FrfModes or None
        Route residues without a modes file: the modes fitted to the FRFs (poles,
        residues, stabilisation diagram), for the report's figures.
    """

    massline: MassLine
    units: dict[str, str]
    mass_given: float | None
    reason: str
    route: str = "massline"
    scaled: ScaledBody | None = None
    routes: tuple[RouteAnswer, ...] = ()
    fitted: FrfModes | None = None


@dataclass(frozen=True)
class RouteAnswer:
    """One FRF route tried by ``--method auto``: whether it applies, its answer, why it was (not) chosen.

    Attributes
    ----------
    route : str
        ``"residues"`` or ``"massline"``.
    applies : bool
        Whether the data allow it (it ran and gave an answer).
    reason : str
        One line: what in the data made it apply, or why not.
    massline : rigidid.core.massline.MassLine or None
        Its answer (with intervals where it has them), when it applies.
    """

    route: str
    applies: bool
    reason: str
    massline: MassLine | None = None


PathLike = str | os.PathLike[str]


@dataclass(frozen=True)
class TestRun:
    """What ``rigidid identify`` computed from a test's files (:func:`rigidid.api.records.identify_test`).

    Attributes
    ----------
    result : IdentifyResult
        The identification (refined on the records where it was).
    estimate : rigidid.core.timedomain.ModalEstimate or None
        The modal estimation, when the modes came from records.
    records : list of (ndarray, float) or None
        The records as read whole (not when the files were read in row blocks).
    spectrum : (ndarray, ndarray) or None
        The records' summed spectrum (frequency in Hz, power), when asked for.
    """

    __test__ = False  # not a pytest class

    result: IdentifyResult
    estimate: ModalEstimate | None = None
    records: list[tuple[NDArray[np.float64], float]] | None = None
    spectrum: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
