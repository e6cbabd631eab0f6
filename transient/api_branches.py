"""The public API on complex modes over a parameter: `mu_map` (a case's complex modes at several
friction coefficients, sharing their stages), `branches` (a mu map's modes linked from one value
to the next) and `sweep_branches` (the same for a cea sweep's folder), each with the table of
its unstable modes and the points where its branches turn unstable."""
from .api_interface import pair_name
from .case.loading import load as _load
from .errors import CaseError


def mu_map(case, mus, pair=None):
    """The complex modes of a case at each of several friction coefficients on one pair,
    sharing the model, the contact's geometry and the factorization (and the basis, for
    variants equal on a ``basis_mu``), as ``transient plot cea --mu`` maps them.

    Parameters
    ----------
    case : Case
        From `load`; its own friction is not among the map's unless given in ``mus``.
    mus : sequence of float
        The friction coefficients (>= 0).
    pair : str, optional
        The pair whose ``friction.mu`` varies; by default the case's first.

    Returns
    -------
    list of Analysis
        One per value of ``mus``, as `cea` returns it.
    """
    from .shared import build_shared, stage_key
    from .stability.stage import analyse, analysed_case
    name = pair_name(case, pair)
    if not len(mus) or min(mus) < 0:
        raise CaseError(case.path, "mus", "expected friction coefficients >= 0")
    # every variant is checked at load before the first analysis (float: NumPy 2's repr of
    # its own floats, np.float64(0.2), is no TOML literal)
    variants = [_load(case.path, list(case.overrides)
                      + [f"contact.{name}.friction.mu={float(mu)!r}"]) for mu in mus]
    built = basis = key = None
    if case.solver.reduction.enabled:
        analysed = analysed_case(case)
        built = build_shared(analysed, "factorization")
        if any(c.friction.basis_mu for c in case.contact.values()):
            basis = build_shared(analysed, "basis", built)
            key = stage_key(case, "basis")
    return [analyse(v, built=basis if key is not None and stage_key(v, "basis") == key
                    else built) for v in variants]


def branches(mus, analyses, parameter="mu"):
    """The complex modes of several analyses linked into branches, as ``transient plot cea
    --mu`` draws them.

    Each mode at one value is linked to a mode at the next by the MAC of their shapes (on a
    few hundred nodes of the model), one to one, the eigenvalue's move breaking the MAC's
    ties (at a coupling point the two modes share one shape); a mode whose shape resembles
    none at the previous value (MAC below 0.5) starts a branch of its own.

    Parameters
    ----------
    mus : sequence of float
        The parameter's value of each analysis (mu_map's ``mus``), in any order.
    analyses : sequence of Analysis
        From `mu_map` (or `cea` of each case), of one model.
    parameter : str
        The values' name: the tables' first column.

    Returns
    -------
    Branches
        ``values`` (ascending), ``branch`` (each mode's branch id at each value),
        ``coupling`` (one dict per point where a branch turns unstable or stable again:
        ``branch``, ``partner`` (the branch it couples with, or None), the parameter's value
        there, ``frequency_hz`` and ``becomes``), ``unstable_modes()`` (one dict per
        unstable mode at each value: the value, ``branch``, ``frequency_hz``, ``real``
        [1/s], ``damping_ratio``), ``line(b)`` (branch b's values and eigenvalues) and
        ``write(unstable_csv, coupling_csv)``.

    Raises
    ------
    CaseError
        Not one analysis per value, or analyses of different models.
    """
    from .stability.branches import step_of, track
    if len(mus) != len(analyses):
        raise CaseError("transient.branches", "mus", f"expected one value per analysis "
                        f"({len(analyses)}), got {len(mus)}")
    if len({a.model.ndof for a in analyses}) > 1:
        raise CaseError("transient.branches", "analyses", "expected the analyses of one "
                        "model (their shapes are compared on its dofs)")
    return track(parameter, [step_of(mu, a) for mu, a in zip(mus, analyses)])


def sweep_branches(directory, x=None):
    """The branches of a cea sweep's complex modes against one of its parameters, as
    ``transient plot sweep`` draws them: one Branches per combination of the other
    parameters' values.

    The modes are linked by the shapes each variant's modes file stores (a few hundred nodes
    of the model), or by the eigenvalue alone for files written before they were stored.

    Parameters
    ----------
    directory : str or Path
        The folder of a sweep of kind ``cea`` or ``both``.
    x : str, optional
        The parameter (a number per variant); by default the sweep's first.

    Returns
    -------
    dict
        The other parameters' values (``"key=value, ..."``, empty for a sweep of one
        parameter) -> Branches, as `branches` returns them, its ``parameter`` x.

    Raises
    ------
    CaseError
        No sweep in the folder, a run sweep, or an x that is not a numeric parameter of it.
    """
    from .plots.sweep import branch_groups
    return branch_groups(directory, x)
