"""The FRF routes: simulated FRFs, modes fitted to FRFs (pLSCF + LSFD), and mass, CG and inertia from the
mass line or from force-scaled residues."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from rigidid.api.load import body_from_file, load_references_for, same_units
from rigidid.errors import InputError
from rigidid.io import files
from rigidid.io.files import ModeTable
from rigidid.models import BodyFile, LayoutFile, ReferencesFile
from rigidid.results import FrfData, MassLineResult, PathLike

if TYPE_CHECKING:
    from rigidid.core.frfmodes import FrfModes
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
    frf: PathLike,
    references: ReferencesFile | PathLike,
    *,
    mass: float | None = None,
    band: tuple[float, float] | None = None,
    modes: PathLike | None = None,
    modes_used: tuple[int, ...] | None = None,
    method: str = "massline",
) -> MassLineResult:
    """Mass, CG and inertia of a body from FRFs by the mass line, or from scaled modes.

    Parameters
    ----------
    layout : LayoutFile or path-like
        The sensors (responses).
    frf : path-like
        FRF CSV (see :func:`rigidid.io.frf.load_frf_csv`), or a UFF file
        (``.uff``/``.unv``, :func:`rigidid.io.frf.load_frf_uff`).
    references : ReferencesFile or path-like
        The force points and directions.
    mass : float, optional
        A known mass to compare the measured one with (overrides the layout's).
    band : (float, float), optional
        Mass-line band (Hz); automatic by default.
    modes : path-like, optional
        ``modes.csv`` of the same test: its rigid-body poles turn the route into
        scaled modes (:func:`rigidid.core.massline.mass_from_residues`).
    modes_used : tuple of int, optional
        The six rigid-body mode labels of `modes` (default: all, if there are six).
    method : {"massline", "residues"}
        ``"residues"`` without `modes`: the six rigid-body poles are fitted to
        the FRFs (:func:`rigidid.core.frfmodes.fit_frf_modes`).

    Returns
    -------
    MassLineResult
    """
    from rigidid.core.massline import mass_line
    from rigidid.io.frf import load_frf_csv, load_frf_uff, reference_arrays

    lay = layout if isinstance(layout, LayoutFile) else files.load_layout(layout)
    refs = load_references_for(references, lay)
    ids, pos, dirs = files.layout_arrays(lay)
    rids, rpos, rdirs = reference_arrays(refs)
    is_uff = str(frf).lower().endswith((".uff", ".unv"))
    if is_uff:
        freqs, h = load_frf_uff(frf, ids, rids, units={"length": lay.units.length, "mass": lay.units.mass})
    else:
        freqs, h = load_frf_csv(frf, ids, rids)
    if mass is not None and not mass > 0.0:
        raise InputError(f"mass must be positive, got {mass}")
    fitted = None
    if modes is None and method == "residues":
        from rigidid.core.frfmodes import fit_frf_modes
        from rigidid.core.massline import mass_from_residues

        fitted = fit_frf_modes(freqs, h, pos, dirs, rpos, rdirs, band=band, n_modes=6)
        poles = fitted.poles
        result = mass_from_residues(freqs, h, pos, dirs, rpos, rdirs, poles, band=band)
        reason = (
            "method residues: residues of the FRFs fitted with the six rigid-body poles found in the FRFs "
            "(pLSCF, stabilisation diagram, refined on the FRFs); their high-frequency limit is T M^-1 T_f^T, "
            "so the mass is measured through the force"
        )
    elif modes is None:
        poles = None
        result = mass_line(freqs, h, pos, dirs, rpos, rdirs, band=band)
        reason = (
            "method massline: the accelerance between the rigid-body and the elastic modes is T M^-1 T_f^T; "
            "the mass is measured through the force, no mounts or mass needed"
        ) + (f"; supports: {result.supports_reason}" if result.supports_reason else "")
    else:
        from rigidid.core.massline import mass_from_residues
        from rigidid.core.statespace import poles_from_modal

        table = files.load_modes(modes, ids)
        labels = modes_used if modes_used is not None else table.labels
        if len(labels) != 6 or any(label not in table.labels for label in labels):
            raise InputError(
                f"scaled modes need six rigid-body modes of the modes file, got labels {list(labels)}",
                source="modes_used",
            )
        cols = [table.labels.index(label) for label in labels]
        poles = poles_from_modal(table.frequency_hz[cols], table.damping_ratio[cols])
        result = mass_from_residues(freqs, h, pos, dirs, rpos, rdirs, poles, band=band)
        reason = (
            "method residues: residues of the FRFs fitted with the six rigid-body poles of the modes file "
            "(scaled modes); their high-frequency limit is T M^-1 T_f^T, so the mass is measured through the force"
        )
    _frf_verdict(result, "mass line" if modes is None and method != "residues" else "residues")
    scaled = None
    if poles is not None:
        from rigidid.core.frfmodes import body_from_frfs, rigid_band

        lam = np.asarray(poles)[np.argsort(np.abs(poles))]
        fit_band = band if band is not None else rigid_band(freqs, h)[0]
        scaled = body_from_frfs(freqs, h, lam, pos, dirs, rpos, rdirs, band=fit_band)
    return MassLineResult(
        result,
        {"length": lay.units.length, "mass": lay.units.mass},
        mass if mass is not None else lay.mass,
        reason,
        "massline" if modes is None and method != "residues" else "residues",
        scaled,
        fitted,
    )


Arr = NDArray[np.float64]


def _frf_verdict(result: MassLine, route: str) -> None:
    """Refuse (IdentificationError) or warn (FrfMisfitWarning) as :func:`rigidid.core.frfstats.verdict` says."""
    from rigidid.core.frfstats import verdict
    from rigidid.errors import emit

    notice = verdict(result.inertia_tensor, result.residual, result.misfit_noise_units, result.misfit_where, route)
    emit([notice] if notice is not None else [], stacklevel=3)


def _load_frf(
    layout: LayoutFile | PathLike, frf: PathLike, references: ReferencesFile | PathLike
) -> tuple[tuple[str, ...], Arr, NDArray[np.complex128], Arr, Arr, Arr, Arr]:
    """Sensor ids, frequencies, FRFs (p, q, f), sensor positions and directions, reference positions and directions."""
    from rigidid.io.frf import load_frf_csv, load_frf_uff, reference_arrays

    lay = layout if isinstance(layout, LayoutFile) else files.load_layout(layout)
    refs = load_references_for(references, lay)
    ids, pos, dirs = files.layout_arrays(lay)
    rids, rpos, rdirs = reference_arrays(refs)
    is_uff = str(frf).lower().endswith((".uff", ".unv"))
    freqs, h = (load_frf_uff if is_uff else load_frf_csv)(frf, ids, rids)
    return ids, freqs, h, pos, dirs, rpos, rdirs


def fit_modes_frf(
    layout: LayoutFile | PathLike,
    frf: PathLike,
    references: ReferencesFile | PathLike,
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
    references : ReferencesFile or path-like
        The force points and directions.
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
