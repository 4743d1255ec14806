"""The measured force of an impact test: the mass it measures, and its H1 FRFs for the FRF routes.

``identify --records`` with a force channel (the layout's ``force`` block, or ``--force COLUMN``)
identifies the body per unit mass from the records as before, then reads the force with the
responses, forms the H1 FRFs (:func:`rigidid.core.timedomain.force.h1_frf`) and fits ``1 / m``
of the identified per-mass body to them (:func:`rigidid.core.timedomain.force.fit_mass`); from
there, the errors-in-variables fit (:func:`rigidid.core.timedomain.force.fit_mass_eiv`: the force's
samples in their window and the responses' spectra in one likelihood) gives the mass. Its standard
error enters the inertia's and the stiffness's.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from rigidid.errors import InputError
from rigidid.models import ForceChannel, LayoutFile
from rigidid.results import IdentifyResult, PathLike

if TYPE_CHECKING:
    from rigidid.core.sensor_budget import SensorBounds
    from rigidid.core.timedomain.force import ForceFrf, ForceMass
    from rigidid.core.timedomain.refine import RecordBound

Array = NDArray[np.float64]

MISFIT_WARN = 3.0
"""Above this misfit (RMS residual over the FRFs' noise) ..."""
RESIDUAL_WARN = 0.02
"""... and this relative residual, a warning says the per-mass body explains the force's FRFs poorly."""


@dataclass(frozen=True)
class ForceOptions:
    """How ``identify --records`` uses a measured force.

    Attributes
    ----------
    column : str or None
        The force channel's column (``--force``); None: the layout's ``force.column``.
    frf_out : path-like or None
        Write the H1 FRFs and their coherence here (``--frf-out``; ``.csv`` or ``.uff``/``.unv``).
    band : (float, float) or None
        Lines the mass is fitted on (Hz); None: automatic
        (:func:`rigidid.core.timedomain.force.fit_band`).
    """

    column: str | None = None
    frf_out: PathLike | None = None
    band: tuple[float, float] | None = None


def force_channel(layout: LayoutFile, options: ForceOptions) -> ForceChannel:
    """The layout's ``force`` block, its column replaced by ``--force`` when given.

    Raises
    ------
    InputError
        No ``force`` block: the drive point is unknown.
    """
    if layout.force is None:
        raise InputError(
            "the force's drive point is unknown: add a 'force' block to layout.json "
            '({"column": ..., "position": [x, y, z], "direction": "+x" or [x, y, z]})',
            source="force",
        )
    if options.column is not None:
        return layout.force.model_copy(update={"column": options.column})
    return layout.force


def check_force(layout: LayoutFile, options: ForceOptions, paths: Sequence[PathLike]) -> None:
    """Before any work: the drive point is known and every record file has the force column.

    Raises
    ------
    InputError
        No ``force`` block (:func:`force_channel`); a file without the force column, naming it.
    """
    from pathlib import Path

    from rigidid.io.records import open_source

    column = force_channel(layout, options).column
    ids = [s.id for s in layout.sensors]
    for path in paths:
        with _named_column(column, str(path)):
            open_source(Path(path), [*ids, column], None)


@contextmanager
def _named_column(column: str, src: str) -> Iterator[None]:
    """The reader's "sensor 'X' of the layout has no column" said of the force column."""
    try:
        yield
    except InputError as exc:
        if f"sensor {column!r} of the layout has no column" in str(exc):
            raise InputError(f"the force column {column!r} is not in the record", source=src) from None
        raise


def read_force_records(
    paths: Sequence[PathLike], sensor_ids: Sequence[str], column: str
) -> tuple[list[Array], list[Array], float]:
    """Responses (layout order of `sensor_ids`) and force of each record file, and the sample interval.

    Raises
    ------
    InputError
        What :func:`rigidid.io.records.read_record` refuses (a record without the force column:
        "sensor 'force' of the layout has no column"), or records of different sample intervals.
    """
    from rigidid.io.records import read_record

    if column in sensor_ids:
        raise InputError(f"the force column {column!r} is a sensor of the layout", source="force")
    responses, forces, steps = [], [], []
    for path in paths:
        with _named_column(column, str(path)):
            data, dt = read_record(path, [*sensor_ids, column])
        responses.append(data[:, :-1])
        forces.append(data[:, -1])
        steps.append(dt)
    if max(steps) - min(steps) > 1e-6 * min(steps):
        raise InputError(
            f"records have different sample intervals ({min(steps):.9g} to {max(steps):.9g} s)", source="force"
        )
    return responses, forces, float(np.mean(steps))


def measure_mass(
    result: IdentifyResult,
    paths: Sequence[PathLike],
    layout: LayoutFile,
    options: ForceOptions,
    bounds: SensorBounds,
) -> tuple[ForceMass, ForceFrf]:
    """The mass the force measures, with the per-mass body of `result`, and the H1 FRFs it came from.

    Parameters
    ----------
    result : IdentifyResult
        The records route's answer (per unit mass is enough; its mass is not used).
    paths : sequence of path-like
        The record files (one per impact), each with the force column.
    layout : LayoutFile
        The sensors, their tolerances and the ``force`` block.
    options : ForceOptions
    bounds : SensorBounds
        The sensors' error bounds (:func:`rigidid.api.records.sensor_bounds`): their sensitivity
        (and the force sensor's, ``force.sensitivity``, by default the same) enters the mass's
        standard error.

    Returns
    -------
    (ForceMass, ForceFrf)
    """
    from rigidid.core.timedomain.force import Windows, fit_band, h1_frf, per_mass_accelerance

    channel = force_channel(layout, options)
    responses, forces, dt = read_force_records(paths, result.sensor_ids, channel.column)
    frf = h1_frf(responses, forces, dt, Windows(channel.force_window, channel.exponential_end))
    ident = result.identification
    s = np.asarray(2j * np.pi * frf.frequency_hz + frf.decay_rate, dtype=complex)
    model = per_mass_accelerance(
        s, result.positions, result.directions, np.asarray(channel.position), np.asarray(channel.unit_direction()),
        center_of_gravity=ident.center_of_gravity, inertia_per_mass=ident.inertia_per_mass,
        stiffness_per_mass=ident.stiffness_per_mass, damping_per_mass=ident.damping_per_mass,
    )  # fmt: skip
    force_bound = channel.sensitivity if channel.sensitivity is not None else bounds.sensitivity
    band = fit_band(frf, np.asarray(ident.frequency_hz), options.band)
    fit = _MassFit(responses, forces, dt, frf, band, options.band is None, bounds.sensitivity, force_bound)
    fitted = fit(model)
    fitted = _with_body_error(fitted, result, frf, fit, channel)
    if fitted.misfit > MISFIT_WARN and fitted.relative_residual > RESIDUAL_WARN:
        import warnings

        from rigidid.errors import ModelMisfitWarning

        warnings.warn(
            f"the identified body explains the force's FRFs poorly (misfit {fitted.misfit:.3g} times their noise, "
            f"{100 * fitted.relative_residual:.3g} % of their size): the mass {fitted.mass:.6g} is doubtful "
            "(its standard error is widened by the misfit); check the drive point and direction",
            ModelMisfitWarning,
            stacklevel=2,
        )
    if not (np.isfinite(fitted.mass) and fitted.mass > 0):
        raise InputError(
            f"the force and the responses give a mass of {fitted.mass:.4g}: is the force's direction "
            "or the force channel's sign right?",
            source="force",
        )
    return fitted, frf


class _MassFit:
    """The mass of a per-mass model: the H1 fit on the rigid-body band, then errors in variables.

    The errors-in-variables fit (:func:`rigidid.core.timedomain.force.fit_mass_eiv`) runs when the band
    is automatic, from its low end up to the hammer tip's limit, where the mass line pins the pulse's
    shape. On a given band the H1 fit is the answer: on the rigid-body band alone the pulse's shape is
    free enough to absorb the per-mass body's errors (on ``benchmarks/force_mass.py`` its ``body`` term
    was 7 % against H1's 0.1 %).
    """

    def __init__(self, responses: list[Array], forces: list[Array], dt: float, frf: ForceFrf,
                 band: tuple[float, float], widen: bool, sensitivity: float, force_bound: float) -> None:  # fmt: skip
        from rigidid.core.timedomain.force import impact_spectra, tip_limit

        self.frf, self.band, self.bounds, self.widen = frf, band, (sensitivity, force_bound), widen
        wide = (band[0], max(band[1], tip_limit(frf)))
        self.spectra = impact_spectra(responses, forces, dt, frf, wide if widen else (0.0, -1.0))
        self.lines = (frf.frequency_hz >= wide[0]) & (frf.frequency_hz <= wide[1])
        self.first: ForceMass | None = None

    def __call__(self, model: NDArray[np.complex128]) -> ForceMass:
        """The mass for `model` (:func:`per_mass_accelerance` at every line of the FRFs); after the first
        call, one search from the first answer with its noise levels (for the perturbed models). When the
        errors-in-variables search fails, the H1 fit is the answer (a perturbed model's: no change)."""
        from rigidid.core.timedomain.force import fit_mass, fit_mass_eiv

        failures = (RuntimeError, np.linalg.LinAlgError, FloatingPointError)
        try:
            if self.first is not None:
                try:
                    return fit_mass_eiv(self.spectra, model[self.lines], self.first,
                                        sigma2=self.first.response_noise)  # fmt: skip
                except failures:
                    return self.first
            start = fit_mass(self.frf, model, self.band, sensitivity=self.bounds[0], force_sensitivity=self.bounds[1])
            if not (self.widen and np.isfinite(start.mass) and start.mass > 0 and self.spectra.frequency_hz.size >= 4):
                return start
            try:
                self.first = fit_mass_eiv(self.spectra, model[self.lines], start, coherence=start.coherence)
            except failures:
                return start
            return self.first
        except ValueError as exc:
            raise InputError(str(exc), source="force") from None


def _body_std(result: IdentifyResult) -> dict[str, Array] | None:
    """Standard errors of the per-mass body (CG, J / m, diagonal of K / m) from the records' bound or the
    linearised errors, None when neither is there."""
    bound, errors = result.record_bound, result.standard_errors
    if bound is not None:
        return {"cg": np.asarray(bound.center_of_gravity.std), "j": np.asarray(bound.inertia.std),
                "k": np.asarray(bound.stiffness_diagonal.std)}  # fmt: skip
    if errors is not None:
        return {"cg": np.asarray(errors.center_of_gravity), "j": np.asarray(errors.inertia),
                "k": np.diag(np.asarray(errors.stiffness))}  # fmt: skip
    return None


def _with_body_error(
    fitted: ForceMass, result: IdentifyResult, frf: ForceFrf, fit: _MassFit, channel: ForceChannel
) -> ForceMass:
    """`fitted` with the per-mass body's standard errors propagated into the mass (budget ``body``).

    Each of the CG's coordinates, the entries of ``J / m`` (symmetric pairs together) and the diagonal
    of ``K / m`` is moved by its standard error, the mass fitted again; the changes add in quadrature
    (the entries taken independent, as the records' bound reports them).
    """
    from rigidid.core.timedomain.force import per_mass_accelerance

    std = _body_std(result)
    if std is None:
        return fitted
    ident = result.identification
    s = np.asarray(2j * np.pi * frf.frequency_hz + frf.decay_rate, dtype=complex)
    base = {
        "cg": np.asarray(ident.center_of_gravity, dtype=float),
        "j": np.asarray(ident.inertia_per_mass, dtype=float),
        "k": np.asarray(ident.stiffness_per_mass, dtype=float),
    }
    moves: list[tuple[str, tuple[int, ...], float]] = [("cg", (i,), float(std["cg"][i])) for i in range(3)]
    moves += [("j", (a, b), float(std["j"][a, b])) for a in range(3) for b in range(a, 3)]
    moves += [("k", (i, i), float(std["k"][i])) for i in range(6)]
    changes = []
    for name, where, sd in moves:
        if not (np.isfinite(sd) and sd > 0):
            continue
        body = {k: v.copy() for k, v in base.items()}
        body[name][where] += sd
        if name == "j" and where[0] != where[1]:
            body[name][where[::-1]] += sd
        model = per_mass_accelerance(
            s, result.positions, result.directions, np.asarray(channel.position),
            np.asarray(channel.unit_direction()), center_of_gravity=body["cg"], inertia_per_mass=body["j"],
            stiffness_per_mass=body["k"], damping_per_mass=np.asarray(ident.damping_per_mass, dtype=float),
        )  # fmt: skip
        changes.append(fit(model).mass - fitted.mass)
    body_sd = float(np.sqrt(np.sum(np.square(changes))))
    budget = {**fitted.budget, "body": body_sd}
    total = float(np.sqrt(sum(v**2 for v in budget.values())))
    return replace(fitted, budget=budget, std=total, noise_std=float(np.hypot(fitted.noise_std, body_sd)))


def with_measured_mass(result: IdentifyResult, measured: ForceMass, mass_given: float | None) -> IdentifyResult:
    """`result` in absolute units with the measured mass, its standard error in the inertia's and stiffness's.

    Parameters
    ----------
    result : IdentifyResult
        Identified per unit mass.
    measured : ForceMass
        From :func:`measure_mass`.
    mass_given : float or None
        The layout's or the ``mass`` option's, reported beside the measured one.

    Returns
    -------
    IdentifyResult
        With ``identification.mass`` the measured mass, ``force_mass`` and ``mass_given`` set;
        the records' bound (``record_bound``) or the linearised standard errors in absolute
        units, each absolute figure's variance ``m^2 var(q) + q^2 var(m)`` (q per mass).
    """
    from rigidid.api import checks

    m, sm = measured.mass, measured.std
    ident = replace(result.identification, mass=m)
    bound = result.record_bound
    if bound is not None and bound.per_mass:
        bound = absolute_bound(bound, m, sm)
    errors = result.standard_errors
    if errors is not None and result.poles is not None and result.shapes is not None:
        errors = checks.standard_errors_of(
            ident, result.positions, result.directions, result.poles, result.shapes,
            replace(errors.noise, mass=sm / m),
        )  # fmt: skip
    return replace(
        result, identification=ident, record_bound=bound, standard_errors=errors, force_mass=measured,
        mass_given=mass_given,
    )  # fmt: skip


def absolute_bound(bound: RecordBound, m: float, sm: float) -> RecordBound:
    """A per-mass records' bound in absolute units, the mass's standard error added.

    Parameters
    ----------
    bound : RecordBound
        Per unit mass (``per_mass`` true).
    m, sm : float
        The mass and its standard error.

    Returns
    -------
    RecordBound
        Inertia, principal moments and stiffness diagonal times `m`, each std
        ``sqrt(m^2 std^2 + q^2 sm^2)``, intervals ``-/+ 1.96 std``; ``sensor_budget``'s inertia
        entries times `m`, and a source ``mass`` (``|J / m| sm``).
    """
    from rigidid.core.uncertainty import IntervalEstimate

    z95 = 1.959963984540054

    def scaled(iv: IntervalEstimate) -> IntervalEstimate:
        est = m * np.asarray(iv.estimate)
        std = np.sqrt((m * np.asarray(iv.std)) ** 2 + (np.asarray(iv.estimate) * sm) ** 2)
        return IntervalEstimate(est, std, est - z95 * std, est + z95 * std)

    budget = bound.sensor_budget
    if budget is not None:
        jpm = np.asarray(bound.inertia.estimate)
        budget = {
            source: {"center_of_gravity": parts["center_of_gravity"], "inertia_per_mass": m * parts["inertia_per_mass"]}
            for source, parts in budget.items()
        }
        budget["mass"] = {"center_of_gravity": np.zeros(3), "inertia_per_mass": np.abs(jpm) * sm}
    return replace(
        bound,
        inertia=scaled(bound.inertia),
        principal_moments=scaled(bound.principal_moments),
        stiffness_diagonal=scaled(bound.stiffness_diagonal),
        per_mass=False,
        sensor_budget=budget,
    )


def write_frf(path: PathLike, frf: ForceFrf, result: IdentifyResult, layout: LayoutFile, options: ForceOptions) -> None:
    """Write the H1 FRFs (``--frf-out``) as the FRF routes read them, and ``references.json`` beside them.

    CSV (``.csv``): the FRF CSV of FORMATS.md with a ``coherence`` column; UFF (``.uff``/``.unv``):
    datasets 164 and 58 as ``simulate --frf`` writes them (no coherence). The lines written run
    from the first above 0 Hz to the hammer tip's limit
    (:func:`rigidid.core.timedomain.force.tip_limit`). ``<stem>.references.json`` gives the drive
    point, its id the force column's name.
    """
    import json
    from pathlib import Path

    from rigidid.core.timedomain.force import tip_limit
    from rigidid.io.atomic import write_bytes_atomic, write_text_atomic
    from rigidid.io.frf import frf_csv_text, frf_format_from, frf_uff_bytes

    channel = force_channel(layout, options)
    f = frf.frequency_hz
    keep = (f > 0) & (f <= tip_limit(frf))
    values = frf.frf[keep].T[:, None, :]
    ref = channel.column
    fmt = frf_format_from(path, None)
    if fmt == "csv":
        coherence = frf.coherence[keep].T[:, None, :]
        write_text_atomic(path, frf_csv_text(f[keep], values, result.sensor_ids, [ref], coherence))
    else:
        content = frf_uff_bytes(
            f[keep], values, result.sensor_ids, result.directions, [ref],
            np.asarray([channel.unit_direction()]), dict(result.units), binary=fmt == "uff",
            name="rigidid identify --frf-out",
        )  # fmt: skip
        write_bytes_atomic(path, content)
    refs = {
        "units": {"length": layout.units.length, "mass": layout.units.mass},
        "references": [{"id": ref, "position": list(channel.position), "direction": list(channel.unit_direction())}],
    }
    target = Path(path)
    write_text_atomic(target.with_name(target.stem + ".references.json"), json.dumps(refs, indent=2) + "\n")
