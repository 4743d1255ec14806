"""The FRF routes: simulated FRFs, modes fitted to FRFs (pLSCF + LSFD), and mass, CG and inertia from the
mass line or from force-scaled residues."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from rigidid.api.load import body_from_file, load_references_for, same_units
from rigidid.errors import InputError
from rigidid.io import files
from rigidid.io.files import ModeTable
from rigidid.models import BodyFile, LayoutFile, ReferencesFile
from rigidid.results import FrfData, MassLineResult, PathLike, RouteAnswer

if TYPE_CHECKING:
    from rigidid.core.frfmodes import FrfModes, ScaledBody
    from rigidid.core.massline import MassLine
    from rigidid.io.files import ModeTable
    from rigidid.progress import ProgressCallback


def simulate_frf(
    body: BodyFile | PathLike,
    layout: LayoutFile | PathLike,
    references: ReferencesFile | PathLike,
    *,
    frequencies: NDArray[np.float64] | None = None,
    noise: float = 0.0,
    seed: int | None = None,
) -> FrfData:
    """Accelerance FRFs of a body on its mounts at the layout's sensors for the references.

    Parameters
    ----------
    body, layout, references : file model or path-like
        ``body.json``, ``layout.json`` and ``references.json``.
    frequencies : ndarray, optional
        Frequency lines (Hz). Default: 2000 lines up to 20 times the highest
        rigid-body frequency.
    noise : float
        Complex noise relative to each value (0.01 = 1 %).
    seed : int, optional
        Seed of the noise.

    Returns
    -------
    FrfData
    """
    from rigidid.core.frf import accelerance
    from rigidid.core.simulate import body_modes
    from rigidid.io.frf import reference_arrays

    lay = layout if isinstance(layout, LayoutFile) else files.load_layout(layout, require_rank=False)
    spec = body if isinstance(body, BodyFile) else files.load_body(body)
    same_units(spec, lay, None if isinstance(body, BodyFile) else str(body))
    refs = load_references_for(references, lay)
    ids, pos, dirs = files.layout_arrays(lay)
    rids, rpos, rdirs = reference_arrays(refs)
    truth = body_from_file(spec)
    if frequencies is None:
        top = 20.0 * float(np.abs(body_modes(truth, pos, dirs).poles).max()) / (2.0 * np.pi)
        frequencies = np.linspace(top / 2000.0, top, 2000)
    if not noise >= 0.0:
        raise InputError(f"noise must be zero or positive, got {noise}")
    rng = np.random.default_rng(seed)
    h = accelerance(truth, pos, dirs, rpos, rdirs, frequencies, noise=noise, rng=rng)
    return FrfData(np.asarray(frequencies, dtype=float), h, ids, rids)


def identify_massline(
    layout: LayoutFile | PathLike,
    frf: PathLike | None,
    references: ReferencesFile | PathLike | None,
    *,
    mass: float | None = None,
    band: tuple[float, float] | None = None,
    modes: PathLike | None = None,
    modes_used: tuple[int, ...] | None = None,
    method: str = "massline",
    units: dict[str, str] | None = None,
    geometry: PathLike | None = None,
) -> MassLineResult:
    """Mass, CG and inertia of a body from FRFs: mass line, residues, or both (``method="auto"``).

    Parameters
    ----------
    layout : LayoutFile or path-like
        The sensors (responses), with their ``references`` if the layout lists
        them; or a UFF file holding geometry (15/2411, 18/2420) and FRFs (58,
        function type 4): sensors from the response nodes and directions,
        references from the reference nodes and directions.
    frf : path-like or None
        FRF CSV (see :func:`rigidid.io.frf.load_frf_csv`), or a UFF file
        (``.uff``/``.unv``, :func:`rigidid.io.frf.load_frf_uff`); None when
        `layout` is a UFF file of FRFs.
    references : ReferencesFile, path-like or None
        The force points and directions. They may come from ``references.json``,
        from the layout's ``references`` list, or from a UFF file's headers:
        every source given must say the same (:func:`load_frf_test`).
    mass : float, optional
        A known mass to compare the measured one with (overrides the layout's).
    band : (float, float), optional
        Mass-line band (Hz); automatic by default.
    modes : path-like, optional
        ``modes.csv`` of the same test: its rigid-body poles turn the route into
        scaled modes (:func:`rigidid.core.massline.mass_from_residues`).
    modes_used : tuple of int, optional
        The six rigid-body mode labels of `modes` (default: all, if there are six).
    method : {"massline", "residues", "auto"}
        ``"residues"`` without `modes`: the six rigid-body poles are fitted to
        the FRFs (:func:`rigidid.core.frfmodes.fit_frf_modes`). ``"auto"``:
        every route the data allow is run and one is chosen
        (:func:`identify_frf_auto`).
    units, geometry
        As for :func:`rigidid.api.load.load_uff` (UFF `layout` only).

    Returns
    -------
    MassLineResult
    """
    lay, refs, data = load_frf_test(layout, frf, references, units=units, geometry=geometry)
    if mass is not None and not mass > 0.0:
        raise InputError(f"mass must be positive, got {mass}")
    if method == "auto" and modes is None:
        return identify_frf_auto(lay, refs, data, mass=mass, band=band)
    if method not in ("massline", "residues", "auto"):
        raise InputError(f"FRFs are identified with method auto, massline or residues, not {method!r}")
    return _identify_route(lay, refs, data, mass=mass, band=band, modes=modes, modes_used=modes_used, method=method)


def _identify_route(
    lay: LayoutFile,
    refs: ReferencesFile,
    data: FrfData,
    *,
    mass: float | None,
    band: tuple[float, float] | None,
    modes: PathLike | None = None,
    modes_used: tuple[int, ...] | None = None,
    method: str,
) -> MassLineResult:
    """One FRF route by name (``massline`` or ``residues``, the latter from `modes` if given), with its verdict."""
    import dataclasses

    from rigidid.io.frf import reference_arrays

    ids, pos, dirs = files.layout_arrays(lay)
    _, rpos, rdirs = reference_arrays(refs)
    freqs, h = data.frequencies, data.frf
    fitted = None
    scaled_band = band  # the scaled modes' band: below an elastic mode left out, else as asked
    if modes is None and method == "residues":
        from rigidid.core.massline import mass_from_residues

        fitted, poles, cut, left_out = _rigid_poles(freqs, h, (pos, dirs, rpos, rdirs), band)
        result = mass_from_residues(freqs, h, pos, dirs, rpos, rdirs, poles, band=cut or band)
        scaled_band = cut or band
        if cut is not None and band is None:
            result = dataclasses.replace(result, band_source="automatic")
        reason = (
            "method residues: residues of the FRFs fitted with the six rigid-body poles found in the FRFs "
            "(pLSCF, stabilisation diagram, refined on the FRFs); their high-frequency limit is T M^-1 T_f^T, "
            "so the mass is measured through the force"
        ) + (f"; {left_out}" if left_out else "")
    elif modes is None:
        poles = None
        result = _mass_line(freqs, h, pos, dirs, rpos, rdirs, band)
        reason = (
            "method massline: the accelerance between the rigid-body and the elastic modes is T M^-1 T_f^T; "
            "the mass is measured through the force, no mounts or mass needed"
        ) + (f"; supports: {result.supports_reason}" if result.supports_reason else "")
    else:
        from rigidid.core.massline import mass_from_residues

        poles = _modes_poles(modes, ids, modes_used)
        result = mass_from_residues(freqs, h, pos, dirs, rpos, rdirs, poles, band=band)
        reason = (
            "method residues: residues of the FRFs fitted with the six rigid-body poles of the modes file "
            "(scaled modes); their high-frequency limit is T M^-1 T_f^T, so the mass is measured through the force"
        )
    route = "massline" if modes is None and method != "residues" else "residues"
    _frf_verdict(result, "mass line" if route == "massline" else "residues")
    _elastic_near(data, result.band)
    scaled = None if poles is None else _scaled_body(data, pos, dirs, rpos, rdirs, poles, scaled_band)
    units: dict[str, str] = {"length": lay.units.length, "mass": lay.units.mass}
    return MassLineResult(result, units, mass if mass is not None else lay.mass, reason, route, scaled, fitted=fitted)


def identify_frf_route(
    lay: LayoutFile,
    refs: ReferencesFile,
    data: FrfData,
    *,
    method: str,
    mass: float | None = None,
    band: tuple[float, float] | None = None,
    modes: PathLike | None = None,
    modes_used: tuple[int, ...] | None = None,
) -> MassLineResult:
    """One FRF route by name on a test loaded once (:func:`load_frf_test`), as :func:`identify_massline` runs it.

    Parameters
    ----------
    lay, refs, data
        The test (:func:`load_frf_test`).
    method : {"massline", "residues"}
    mass, band, modes, modes_used
        As :func:`identify_massline`.

    Returns
    -------
    MassLineResult
    """
    if method not in ("massline", "residues"):
        raise InputError(f"an FRF route is massline or residues, not {method!r}", source="--method")
    return _identify_route(lay, refs, data, mass=mass, band=band, modes=modes, modes_used=modes_used, method=method)


ELASTIC_APART = 1.5
"""A mode is left out as elastic only when it lies this factor above the highest rigid-body one: close
and heavily damped rigid modes blur each other's fitted shapes (regime matrix, 10 % mount damping: the
two highest rigid modes' shapes fitted rigid motion to 0.27 and 0.67)."""


def _rigid_poles(
    freqs: Arr, h: NDArray[np.complex128], geometry: tuple[Arr, Arr, Arr, Arr], band: tuple[float, float] | None
) -> tuple[FrfModes, NDArray[np.complex128], tuple[float, float] | None, str]:
    """The six rigid-body poles fitted to the FRFs, an elastic mode among them fitted and left out.

    Returns the modes fitted, the six rigid-body poles, the residues' band when it must stop below an
    elastic mode (half its frequency; else None) and a phrase saying so (else empty).

    A shape fitting rigid motion worse than ``SUSPECT_RESIDUAL`` (:mod:`rigidid.core.selection`) asks for a
    seventh mode: when seven leave six rigid ones below a clearly elastic one (:data:`ELASTIC_APART` above
    them), the six are taken.

    Raises
    ------
    IdentificationError
        A fitted mode stands out as elastic (``elastic_suspect``) and no seventh mode leaves six rigid ones
        below it, or the elastic mode lies too close above the rigid ones for a band between them (naming it).
    """
    from rigidid.core.frfmodes import fit_frf_modes, rigid_six
    from rigidid.core.massline import RESIDUES_BAND_RATIO
    from rigidid.core.selection import SUSPECT_RESIDUAL
    from rigidid.errors import IdentificationError

    pos, dirs = geometry[0], geometry[1]
    fitted = fit_frf_modes(freqs, h, *geometry, band=band, n_modes=6)
    six, residuals = rigid_six(fitted, pos, dirs)
    bad = int(np.argmax(residuals))
    hz = np.sort(fitted.frequency_hz)
    if six is None and not (bad == 5 and hz[5] >= ELASTIC_APART * hz[4]):
        six = np.arange(6)  # close, damped rigid modes blur each other's shapes: no elastic mode among them
    if six is not None and not residuals.max() > SUSPECT_RESIDUAL:
        return fitted, fitted.poles, None, ""
    what = (
        f"the FRFs hold a mode at {fitted.frequency_hz[bad]:.4g} Hz whose shape is not a rigid-body motion "
        f"(rigid-fit residual {residuals[bad]:.2g}, the others' at most {np.sort(residuals)[-2]:.2g})"
    )
    try:  # a seventh mode: the elastic one fitted with the six rigid ones (or a rigid one it hid)
        seven = fit_frf_modes(freqs, h, *geometry, band=band, n_modes=7)
        six7, res7 = rigid_six(seven, pos, dirs)
    except IdentificationError as exc:
        if six is None:
            raise IdentificationError(f"{what}, and no seventh stable mode to take its place ({exc})") from exc
        return fitted, fitted.poles, None, ""
    if six7 is None or seven.frequency_hz[np.setdiff1d(np.arange(7), six7)[0]] < ELASTIC_APART * max(
        seven.frequency_hz[six7]
    ):
        if six is None:
            raise IdentificationError(f"{what}, and seven modes do not leave six rigid ones below it: give the band")
        return fitted, fitted.poles, None, ""
    out = int(np.setdiff1d(np.arange(7), six7)[0])
    f_el, top = float(seven.frequency_hz[out]), float(np.max(seven.frequency_hz[six7]))
    hi = 0.5 * f_el if band is None else min(0.5 * f_el, band[1])
    if hi < RESIDUES_BAND_RATIO * top:
        raise IdentificationError(
            f"the FRFs hold a 7th mode at {f_el:.4g} Hz inside the band, {f_el / top:.2g}x the highest rigid-body "
            f"mode ({top:.4g} Hz), its shape not a rigid-body motion (rigid-fit residual {res7[out]:.2g}): the "
            f"residues need a band clear of it (to half its frequency) reaching {RESIDUES_BAND_RATIO:g}x the highest "
            "rigid-body mode, and the mass line a band from 3x that mode below it"
        )
    lo = float(freqs[0]) if band is None else band[0]
    note = (
        f"a 7th mode at {f_el:.4g} Hz in the band, its shape not a rigid-body motion (rigid-fit residual "
        f"{res7[out]:.2g}), fitted with the six and left out: residues fitted up to half its frequency"
    )
    return seven, seven.poles[six7], (lo, hi), note


def _mass_line(
    freqs: Arr, h: NDArray[np.complex128], pos: Arr, dirs: Arr, rpos: Arr, rdirs: Arr, band: tuple[float, float] | None
) -> MassLine:
    """:func:`rigidid.core.massline.mass_line`; FRFs without a resonance peak but flat (free-free data measured
    above the suspension modes) get the plateau as their band (``band_source`` ``"plateau"``)."""
    import dataclasses

    from rigidid.core.frfband import plateau_band
    from rigidid.core.massline import mass_line

    plateau = plateau_band(freqs, h) if band is None else None
    if plateau is None:
        return mass_line(freqs, h, pos, dirs, rpos, rdirs, band=band)
    return dataclasses.replace(mass_line(freqs, h, pos, dirs, rpos, rdirs, band=plateau), band_source="plateau")


def _elastic_near(data: FrfData, band: tuple[float, float]) -> None:
    """Warn (ElasticNearBandWarning) when the FRFs rise over the top fifth of `band` (an elastic mode just above)."""
    import warnings

    from rigidid.core.frfband import PLATEAU_SLOPE, top_slope
    from rigidid.errors import ElasticNearBandWarning

    slope = top_slope(data.frequencies, data.frf, band)
    if slope > PLATEAU_SLOPE:
        warnings.warn(
            f"the FRFs rise towards the top of the band {band[0]:.4g}-{band[1]:.4g} Hz (log-log slope {slope:.2g}, "
            "flat above the rigid-body modes): an elastic mode just above it biases the answer beyond its interval; "
            "measure further up or end the band lower (--band)",
            ElasticNearBandWarning,
            stacklevel=3,
        )


def _modes_poles(modes: PathLike, ids: tuple[str, ...], modes_used: tuple[int, ...] | None) -> NDArray[np.complex128]:
    """The six rigid-body poles of ``modes.csv`` (the labels `modes_used`, or all six)."""
    from rigidid.core.statespace import poles_from_modal

    table = files.load_modes(modes, ids)
    labels = modes_used if modes_used is not None else table.labels
    if len(labels) != 6 or any(label not in table.labels for label in labels):
        raise InputError(
            f"scaled modes need six rigid-body modes of the modes file, got labels {list(labels)}",
            source="modes_used",
        )
    cols = [table.labels.index(label) for label in labels]
    return np.asarray(poles_from_modal(table.frequency_hz[cols], table.damping_ratio[cols]), dtype=complex)


def _scaled_body(
    data: FrfData, pos: Arr, dirs: Arr, rpos: Arr, rdirs: Arr, poles: NDArray[np.complex128],
    band: tuple[float, float] | None,
) -> ScaledBody:  # fmt: skip
    """The body from the six force-scaled rigid-body modes (stiffness and damping included)."""
    from rigidid.core.frfmodes import body_from_frfs, rigid_band

    lam = np.asarray(poles)[np.argsort(np.abs(poles))]
    fit_band = band if band is not None else rigid_band(data.frequencies, data.frf)[0]
    return body_from_frfs(data.frequencies, data.frf, lam, pos, dirs, rpos, rdirs, band=fit_band)


Arr = NDArray[np.float64]

AUTO_ROUTES = ("residues", "massline")
"""The routes ``method="auto"`` tries, in order."""

NO_PEAKS = (
    "no rigid-body peak: the accelerance is flat up to the first peak or the band's end (free-free, above "
    "the suspension modes): no rigid-body poles to fit"
)
"""Why the residues route does not apply to a plateau (:func:`rigidid.core.frfband.plateau_band`)."""


def identify_frf_auto(
    lay: LayoutFile, refs: ReferencesFile, data: FrfData, *, mass: float | None = None,
    band: tuple[float, float] | None = None,
) -> MassLineResult:  # fmt: skip
    """Every FRF route the data allow, run; one chosen; a warning when two disagree beyond their intervals.

    As :func:`frf_auto_routes`, the chosen route's answer alone.

    Parameters
    ----------
    lay, refs, data, mass, band
        As :func:`frf_auto_routes`.

    Returns
    -------
    MassLineResult
        The chosen route's answer; ``routes`` lists every route tried.
    """
    return frf_auto_routes(lay, refs, data, mass=mass, band=band)[0]


def frf_auto_routes(
    lay: LayoutFile, refs: ReferencesFile, data: FrfData, *, mass: float | None = None,
    band: tuple[float, float] | None = None,
) -> list[MassLineResult]:  # fmt: skip
    """Every FRF route the data allow, run; one chosen; a warning when two disagree beyond their intervals.

    The residues route applies when six stable rigid-body modes are found in
    the band (:func:`rigidid.core.frfmodes.fit_frf_modes`); the mass line when
    a band above the rigid-body peaks and below the elastic ones is found
    (:func:`rigidid.core.massline.mass_line`, which fits the supports exactly
    when they reach near the band). A route the data do not allow, or whose
    verdict refuses its answer, is listed with the one-line reason.

    Parameters
    ----------
    lay, refs, data
        The test (:func:`load_frf_test`).
    mass : float, optional
        A known mass to compare the measured one with.
    band : (float, float), optional
        The band every route uses (automatic by default).

    Returns
    -------
    list of MassLineResult
        The chosen route's answer first (``routes`` lists every route tried),
        then each other route that ran, in the order tried (the report draws
        them without running them again). The choice: among routes whose misfit the noise explains (at most 1.5
        noise units) and that raised no warning of their own (clean
        diagnostics), the one with the narrowest 95 % mass interval (a route
        without intervals last); the reason is in ``reason``.

    Raises
    ------
    IdentificationError
        No route applies (the message lists each route's reason).

    Warns
    -----
    FrfRoutesDisagreeWarning
        Two routes with intervals whose mass, CG or inertia diagonal differ by
        more than the sum of their 95 % half-widths, naming the route the diagnostics blame (the larger
        misfit in noise units; else the one that raised a warning). The chosen route's own warnings are
        passed on.
    """
    import warnings

    from rigidid.errors import IdentificationError, RigididWarning

    answers: list[RouteAnswer] = []
    ran: dict[str, tuple[MassLineResult, list[warnings.WarningMessage]]] = {}
    from rigidid.core.frfband import plateau_band

    flat = band is None and plateau_band(data.frequencies, data.frf) is not None
    for route in AUTO_ROUTES:
        if route == "residues" and flat:
            answers.append(RouteAnswer(route, False, NO_PEAKS))
            continue
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                result = _identify_route(lay, refs, data, mass=mass, band=band, method=route)
        except IdentificationError as exc:
            answers.append(RouteAnswer(route, False, str(exc)))
            continue
        ran[route] = (result, list(caught))
        answers.append(RouteAnswer(route, True, _applies_because(result), result.massline))
    if not ran:
        raise IdentificationError("no FRF route applies: " + "; ".join(f"{a.route}: {a.reason}" for a in answers))
    flags = {
        k: sorted({w.category.__name__ for w in v[1] if issubclass(w.category, RigididWarning)}) for k, v in ran.items()
    }
    chosen, why = _choose_route({k: v[0] for k, v in ran.items()}, flags)
    result, caught = ran[chosen]
    for w in caught:
        warnings.warn(w.message, w.category, stacklevel=2)
    _disagreement({k: v[0] for k, v in ran.items()}, flags)
    reason = f"method auto: {chosen} chosen ({why}); {result.reason}"
    first = MassLineResult(
        result.massline,
        result.units,
        result.mass_given,
        reason,
        result.route,
        result.scaled,
        tuple(answers),
        result.fitted,
    )
    return [first, *(v[0] for k, v in ran.items() if k != chosen)]


def _applies_because(result: MassLineResult) -> str:
    """One line: what in the data let a route run."""
    ml = result.massline
    if result.route == "residues":
        return f"six stable rigid-body modes in the FRFs; residues fitted in {ml.band[0]:.4g}-{ml.band[1]:.4g} Hz"
    text = f"a mass-line band {ml.band[0]:.4g}-{ml.band[1]:.4g} Hz ({ml.band_source}) clear of the resonances"
    return text + (f"; supports {ml.supports}: {ml.supports_reason}" if ml.supports_reason else "")


def _mass_halfwidth(result: MassLineResult) -> float:
    """Relative 95 % half-width of the mass (infinite without intervals)."""
    iv = result.massline.intervals
    if iv is None:
        return float("inf")
    return float((iv.mass.high - iv.mass.low) / 2.0 / abs(result.massline.mass))


def _choose_route(ran: dict[str, MassLineResult], flags: dict[str, list[str]] | None = None) -> tuple[str, str]:
    """The route to report and why (one phrase).

    Preferred: routes whose misfit the noise explains (at most 1.5 noise units) and whose diagnostics are
    clean (no warning of their own, `flags`: the warning categories per route); among them the narrowest
    95 % mass interval.
    """
    if len(ran) == 1:
        only = next(iter(ran))
        return only, "the only route the data allow"
    flags = flags or {}

    def explained(r: MassLineResult) -> bool:
        units = r.massline.misfit_noise_units
        return units is None or units <= 1.5

    fits = [k for k, r in ran.items() if explained(r)] or list(ran)
    clean = [k for k in fits if not flags.get(k)] or fits
    best = min(clean, key=lambda k: _mass_halfwidth(ran[k]))
    widths = ", ".join(
        f"{k} +-{100 * _mass_halfwidth(r):.2g} %" if np.isfinite(_mass_halfwidth(r)) else f"{k} none"
        for k, r in ran.items()
    )
    left = [k for k in ran if k not in fits]
    tail = f"; {', '.join(left)} misfit beyond the noise" if left else ""
    warned = [f"{k} ({', '.join(flags[k])})" for k in fits if k not in clean]
    tail += f"; {', '.join(warned)} warned about" if warned else ""
    return best, f"narrowest 95 % mass interval: {widths}{tail}"


def _disagreement(ran: dict[str, MassLineResult], flags: dict[str, list[str]] | None = None) -> None:
    """Warn (FrfRoutesDisagreeWarning) when two routes differ beyond the sum of their 95 % half-widths."""
    import warnings

    from rigidid.errors import FrfRoutesDisagreeWarning

    names = list(ran)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            what = _beyond(ran[a].massline, ran[b].massline)
            if what is None:
                continue
            ua, ub = ran[a].massline.misfit_noise_units, ran[b].massline.misfit_noise_units
            if ua is not None and ub is not None and max(ua, ub) > 1.2 * min(ua, ub):
                blame = f"the diagnostics blame {a if ua > ub else b} (misfit {max(ua, ub):.3g} noise units " + (
                    f"against {min(ua, ub):.3g})"
                )
            elif flags and bool(flags.get(a)) != bool(flags.get(b)):
                bad = a if flags.get(a) else b
                blame = f"the diagnostics blame {bad} ({', '.join(flags[bad])}; the misfits do not tell)"
            else:
                blame = "the misfits do not tell which (both explained by the noise)"
            warnings.warn(
                f"routes {a} and {b} disagree beyond their 95 % intervals on {what}: {blame}",
                FrfRoutesDisagreeWarning,
                stacklevel=3,
            )


def _beyond(a: MassLine, b: MassLine) -> str | None:
    """The first of mass, CG, inertia diagonal where `a` and `b` differ by more than their 95 % half-widths.

    None when they agree, or when either has no intervals (the exact support fit has none yet).
    """
    pairs = [
        ("the mass", np.atleast_1d(a.mass), np.atleast_1d(b.mass), "mass"),
        ("the CG", a.center_of_gravity, b.center_of_gravity, "center_of_gravity"),
        ("the inertia diagonal", np.diag(a.inertia_tensor), np.diag(b.inertia_tensor), "inertia_tensor"),
    ]
    for label, va, vb, key in pairs:
        width = np.zeros(va.shape)
        for ml in (a, b):
            if ml.intervals is not None:
                iv = getattr(ml.intervals, key)
                half = np.asarray((iv.high - iv.low) / 2.0, dtype=float)
                width = width + (np.diag(half) if key == "inertia_tensor" else np.atleast_1d(half))
        if a.intervals is None or b.intervals is None:  # a route without an interval cannot be judged by it
            return None
        width = width + 1e-8 * max(float(np.max(np.abs(va))), float(np.max(np.abs(vb))), 1e-300)  # rounding
        if np.any(np.abs(va - vb) > width):
            k = int(np.argmax(np.abs(va - vb) - width))
            return f"{label} ({va[k]:.6g} against {vb[k]:.6g})"
    return None


def _frf_verdict(result: MassLine, route: str) -> None:
    """Refuse (IdentificationError) or warn (FrfMisfitWarning) as :func:`rigidid.core.frfstats.verdict` says.

    Also warn (FrfPeakBiasWarning) when the FRFs fall short of the fit at the peaks
    (:func:`rigidid.core.massline.peak_notice`).
    """
    from rigidid.core.frfstats import verdict
    from rigidid.core.massline import peak_notice
    from rigidid.errors import emit

    notice = verdict(result.inertia_tensor, result.residual, result.misfit_noise_units, result.misfit_where, route)
    emit([n for n in (notice, peak_notice(result, route)) if n is not None], stacklevel=3)


def _load_frf(
    layout: LayoutFile | PathLike, frf: PathLike | None, references: ReferencesFile | PathLike | None
) -> tuple[tuple[str, ...], Arr, NDArray[np.complex128], Arr, Arr, Arr, Arr]:
    """Sensor ids, frequencies, FRFs (p, q, f), sensor positions and directions, reference positions and directions."""
    from rigidid.io.frf import reference_arrays

    lay, refs, data = load_frf_test(layout, frf, references)
    ids, pos, dirs = files.layout_arrays(lay)
    _, rpos, rdirs = reference_arrays(refs)
    return ids, data.frequencies, data.frf, pos, dirs, rpos, rdirs


def load_frf_test(
    layout: LayoutFile | PathLike,
    frf: PathLike | None = None,
    references: ReferencesFile | PathLike | None = None,
    *,
    units: dict[str, str] | None = None,
    geometry: PathLike | None = None,
) -> tuple[LayoutFile, ReferencesFile, FrfData]:
    """The layout, its references and its FRFs, from a UFF file of FRFs or from a layout and an FRF file.

    Parameters
    ----------
    layout : LayoutFile or path-like
        ``layout.json``, or a UFF file with geometry (15/2411, 18/2420) and
        FRFs (58, function type 4).
    frf : path-like or None
        The FRFs (CSV or UFF) of a ``layout.json``; None (or `layout` itself) for a UFF `layout`.
    references : ReferencesFile, path-like or None
        ``references.json``.
    units, geometry
        As for :func:`rigidid.api.load.load_uff`.

    Returns
    -------
    layout : LayoutFile
    references : ReferencesFile
        From ``references.json``, the layout's ``references`` list, or the
        UFF FRFs' headers (reference node and direction, with the node's
        coordinates from the UFF file or from the layout's sensor at that
        node): whichever are given; they must agree (ids, positions to 1e-5 of
        the layout's size, UFF keeping 6 digits, and directions).
    frf : FrfData
        Sensors in layout order, references in the returned references' order.

    Raises
    ------
    InputError
        No references from any source; two sources that disagree (naming both
        and the reference); or what the readers raise.
    """
    from rigidid.api.load import UFF_SUFFIXES, check_uff_options, load_uff

    if not isinstance(layout, LayoutFile) and Path(layout).suffix.lower() in UFF_SUFFIXES:
        if frf is not None and Path(frf).resolve() != Path(layout).resolve():
            raise InputError("with a UFF file of FRFs as LAYOUT, give no other --frf file", source="--frf")
        test = load_uff(layout, units=units, geometry=geometry)
        if test.frf is None:
            raise InputError("no FRFs (datasets 58, function type 4) in the file", source=str(layout))
        sources = [(f"{Path(layout).name}'s FRF headers", ReferencesFile(references=test.layout.references or []))]
        if references is not None:
            sources.insert(0, (str(references), load_references_for(references, test.layout)))
        chosen = _agreed_references(sources, test.layout)
        return test.layout, chosen, _reordered(test.frf, chosen)
    if not isinstance(layout, LayoutFile):
        check_uff_options(layout, units, geometry)
    if frf is None:
        raise InputError("FRFs are given with --frf FILE (CSV or UFF), or as a UFF file of FRFs", source="--frf")
    lay = layout if isinstance(layout, LayoutFile) else files.load_layout(layout)
    sources = []
    if references is not None:
        sources.append((str(references), load_references_for(references, lay)))
    if lay.references:
        sources.append(("the layout's references", ReferencesFile(references=lay.references)))
    from rigidid.io.frf import load_frf_csv, read_frf_uff, reference_arrays

    lay_units: dict[str, str] = {"length": lay.units.length, "mass": lay.units.mass}
    uff = read_frf_uff(frf, lay, units=lay_units) if str(frf).lower().endswith((".uff", ".unv")) else None
    if uff is not None and uff.references is not None:  # the file is read once: headers and FRFs
        sources.append((f"{Path(frf).name}'s FRF headers", uff.references))
    refs = _agreed_references(sources, lay)
    ids, rids = tuple(s.id for s in lay.sensors), reference_arrays(refs)[0]
    freqs, h = load_frf_csv(frf, ids, rids) if uff is None else uff.frf(ids, rids, units=lay_units)
    return lay, refs, FrfData(freqs, h, ids, rids)


def _reordered(data: FrfData, refs: ReferencesFile) -> FrfData:
    """`data` with its references in the order of `refs` (matched by node and axis, see :func:`_reference_key`)."""
    keys = [_reference_key(r.id, r.unit_direction()) for r in refs.references]
    have = {k: j for j, k in enumerate(_reference_key(r, None) for r in data.reference_ids)}
    order = [have.get(k, have.get((k[0], None), -1)) for k in keys]
    if -1 in order:
        missing = refs.references[order.index(-1)].id
        raise InputError(f"reference {missing} has no FRF in the file", source="--references")
    if order == list(range(len(order))):
        return FrfData(data.frequencies, data.frf, data.sensor_ids, tuple(r.id for r in refs.references))
    return FrfData(data.frequencies, data.frf[:, order], data.sensor_ids, tuple(r.id for r in refs.references))


def _reference_key(rid: str, direction: tuple[float, float, float] | None) -> tuple[str, str | None]:
    """What a reference id means: its UFF node and signed axis (``"12+x"``, or ``"12"`` with an axis direction).

    Ids that are no UFF node (``"h1"``) are their own key.
    """
    from rigidid.io.uff_codes import ID_PATTERN

    match = ID_PATTERN.match(rid)
    if match is None:
        return rid, None
    axis = match.group(2)
    if axis:
        return match.group(1), (axis.lower() if axis[0] in "+-" else "+" + axis.lower())
    if direction is None:
        return match.group(1), None
    d = np.asarray(direction, dtype=float)
    k = int(np.argmax(np.abs(d)))
    if abs(abs(d[k]) - 1.0) > 1e-9:
        return match.group(1), None
    return match.group(1), ("+" if d[k] > 0 else "-") + "xyz"[k]


def _agreed_references(sources: list[tuple[str, ReferencesFile]], lay: LayoutFile) -> ReferencesFile:
    """The first source's references, once every other source is checked to say the same.

    Raises
    ------
    InputError
        No source; or two that differ in their references, a position (beyond
        1e-5 of the layout's size: UFF keeps 6 digits) or a direction, naming both.
    """
    if not sources:
        raise InputError(
            "no references (force points): list them in the layout's `references`, give --references "
            "REFS.json, or give the FRFs as a UFF file whose headers name the reference nodes",
            source="--references",
        )
    first_name, first = sources[0]
    scale = max([1.0, *(abs(v) for s in lay.sensors for v in s.position)])
    # the same ids are paired by id; else by what they mean (UFF node and axis: "12" along +x is "12+x")
    for name, other in sources[1:]:
        by_id = {r.id for r in first.references} == {r.id for r in other.references}
        mine = {r.id if by_id else _reference_key(r.id, r.unit_direction()): r for r in first.references}
        theirs = {r.id if by_id else _reference_key(r.id, r.unit_direction()): r for r in other.references}
        if set(mine) != set(theirs):
            a = ", ".join(r.id for r in first.references)
            b = ", ".join(r.id for r in other.references)
            raise InputError(f"references {a} ({first_name}) differ from {b} ({name})", source="--references")
        for key, ref in mine.items():
            them = theirs[key]
            if not np.allclose(ref.position, them.position, rtol=0.0, atol=1e-5 * scale):
                raise InputError(
                    f"reference {ref.id} is at {list(ref.position)} in {first_name} but at "
                    f"{list(them.position)} in {name}",
                    source="--references",
                )
            if not np.allclose(ref.unit_direction(), them.unit_direction(), rtol=0.0, atol=1e-5):
                raise InputError(
                    f"reference {ref.id} acts along {ref.direction} in {first_name} but along {them.direction} "
                    f"in {name}",
                    source="--references",
                )
    return first


def fit_modes_frf(
    layout: LayoutFile | PathLike,
    frf: PathLike,
    references: ReferencesFile | PathLike | None,
    *,
    band: tuple[float, float] | None = None,
    n_modes: int | None = None,
    max_order: int | None = None,
    progress: ProgressCallback | None = None,
) -> tuple[ModeTable, FrfModes]:
    """Modes from FRFs (``rigidid modes LAYOUT --frf FRF --references REFS``).

    Parameters
    ----------
    layout : LayoutFile or path-like
        The sensors (responses).
    frf : path-like
        FRF CSV or UFF (as :func:`identify_massline`).
    references : ReferencesFile, path-like or None
        The force points and directions (or from the layout or UFF headers, as
        :func:`load_frf_test`).
    band : (float, float), optional
        Band of the fit (Hz); default from the FRF peaks
        (:func:`rigidid.core.frfmodes.rigid_band`).
    n_modes : int, optional
        Modes to keep (default: every stable mode of the band).
    max_order : int, optional
        Highest pLSCF order.
    progress : ProgressCallback, optional
        Progress of the order sweep.

    Returns
    -------
    modes : ModeTable
        Labelled 1.. in ascending frequency; shapes of the six lowest modes
        scaled to unity modal A by the force (see ``FrfModes.scaled``).
    fitted : rigidid.core.frfmodes.FrfModes
    """
    from rigidid.core.frfmodes import fit_frf_modes
    from rigidid.io.files import ModeTable

    ids, freqs, h, pos, dirs, rpos, rdirs = _load_frf(layout, frf, references)
    fitted = fit_frf_modes(
        freqs, h, pos, dirs, rpos, rdirs, band=band, n_modes=n_modes, max_order=max_order, progress=progress
    )
    table = ModeTable.numbered(fitted.frequency_hz, fitted.damping_ratio, ids, fitted.shapes)
    return table, fitted
