"""The public Python API: what a script or a notebook calls and what every command of the
command line calls before it prints. A thin layer over the stages: each function takes a case
(`load`'s) or a run's history, runs the stages it needs and returns a plain object of arrays.

Here: `transient.load`, `prepare`, `run`, `modes`, `cea` and `sweep`; on an interface,
`compat` and `compat_pairs` (api_interface); on a run's history, `history`, `summary`, `export`
and `modal_growth` (api_results); studies of a case, `bench` and `compare_modes` (api_studies);
complex modes over a parameter, `mu_map`, `branches` and `sweep_branches` (api_branches).

The stages' modules (Numba, SciPy) are imported by the functions that need them, so that
`import transient` stays light and a case's bad input is refused before they load.
"""
from dataclasses import dataclass
from pathlib import Path

from .api_branches import branches, mu_map, sweep_branches
from .api_interface import InterfaceCompatibility, compat, compat_pairs
from .api_results import export, history, modal_growth, summary
from .api_studies import Bench, bench, compare_modes
from .case.checks import check_transient
from .case.loading import literal, on_cluster
from .case.loading import load as _load
from .case.sizes import Cluster
from .errors import CaseError

__all__ = ["load", "prepare", "run", "modes", "cea", "mu_map", "compat", "compat_pairs",
           "sweep", "history", "summary", "export", "modal_growth", "bench", "compare_modes",
           "NormalModes", "InterfaceCompatibility", "Campaign", "Bench", "branches",
           "sweep_branches"]


def load(path, overrides=(), workers=0, scheduler=None):
    """Read, override and validate a case file.

    Parameters
    ----------
    path : str or Path
        The case's TOML file.
    overrides : sequence of str
        ``"dotted.key=TOML_LITERAL"`` assignments applied before validation, as the command
        line's ``--set`` (``"solver.t_end=2e-3"``).
    workers, scheduler
        Where the components path will reduce the parts, as `prepare` takes them: the
        memory bound at load is then each process's (this one's as the cluster's client, a
        part's or a piece's on a worker). A case used elsewhere is checked again there.

    Returns
    -------
    Case
        The frozen specs of every table, defaults filled, in SI units; a reduction whose
        ``method`` is ``"auto"`` has it chosen (``Case.reduction_auto`` says why).

    Raises
    ------
    CaseError
        Any bad input: it names the file, the key and what was expected.
    """
    return _load(path, list(overrides), Cluster.of(workers, scheduler))


def prepare(case, workers=0, scheduler=None, cache=None, on_part=None, on_stage=None):
    """The stages of a case up to its time integration, in memory.

    The model, the contact pairs, the factorization, the preload, the linearization and,
    when the case asks for it, the reduction and the sampling: each runs only if the scene
    needs it.

    Parameters
    ----------
    case : Case
        From `load`.
    workers : int
        With ``solver.reduction.method = "components"``: reduce the parts on an embedded
        Dask cluster of this many one-thread worker processes, one task a part (0: in this
        process).
    scheduler : str, optional
        Or on an existing Dask cluster at this address (``tcp://HOST:PORT``).
    cache : str or Path, optional
        A folder where each part's reduction is kept under the key of what it is made from,
        and read back when a later case makes the same part (a pad campaign reduces the pad
        alone).
    on_part : callable, optional
        ``on_part(name, seconds, cached)`` as each part is reduced or read back.
    on_stage : callable, optional
        ``on_stage(name, seconds, peak_gb)`` as each stage of the setup ends (the model, the
        contact, the factorization, ..., and the components path's coupling), with the
        process's peak memory so far [GB].

    Returns
    -------
    Setup
        ``system`` (the frozen reduced or full system), ``state`` (its initial state),
        ``model`` (the model's sparse stiffness ``model.K`` and mass ``model.M`` [SI], its
        ``fixed`` dofs), ``basis`` (a reduced model's coordinates on the model's dofs),
        ``stages`` (seconds of each stage) and ``meta`` (what the stages report).
    """
    from .stages import prepare as prepare_stages
    from .reduce.engine import engine_for
    case = on_cluster(case, Cluster.of(workers, scheduler))
    with engine_for(case, workers, scheduler, cache, on_part, on_stage) as parts:
        return prepare_stages(case, parts=parts)


def run(case, path=None, resume=False, progress=False, key=None, workers=0, scheduler=None,
        cache=None, on_part=None, on_stage=None):
    """Integrate a case to ``solver.t_end``, streaming its history to an HDF5 file.

    Parameters
    ----------
    case : Case
        From `load`.
    path : str or Path, optional
        The history; by default ``output.file`` of the case, or the case's name with
        ``.h5``, next to the case file.
    resume : bool
        Continue the run the history holds (it must be of the same case) instead of
        starting anew; a resumed run equals a fresh one bit for bit.
    progress : bool
        Show a progress bar on standard error.
    key : str, optional
        What errors call the path (the command line's ``-o``); by default ``path``, or
        ``output.file`` when the path is the case's.
    workers, scheduler, cache, on_part, on_stage
        Where the components path reduces its parts, and what is said meanwhile, as
        `prepare` says.

    Returns
    -------
    RunResult
        ``path`` (the history), ``status`` (``complete``, or ``aborted: REASON`` for a run
        that stopped early and kept its history), ``steps``, ``t_end`` [s], ``dt`` [s],
        ``dt_critical`` [s], ``energy_drift``, ``stages`` and ``timings`` [s]; ``summary()``
        is what ``transient run --json`` prints.
    """
    check_transient(case)           # before the stages' modules (Numba, SciPy) are imported
    case = on_cluster(case, Cluster.of(workers, scheduler))
    from .integration import run as run_case
    if path is None:
        path = case.directory / (case.output.file or Path(case.path).with_suffix(".h5").name)
        key = key or "output.file"
    from .reduce.engine import engine_for
    with engine_for(case, workers, scheduler, cache, on_part, on_stage) as parts:
        return run_case(case, Path(path), resume=resume, progress=progress, key=key or "path",
                        parts=parts)


@dataclass(frozen=True)
class NormalModes:
    """The normal modes of a case with its contact pairs tied (`modes`)."""
    frequencies: object      # (n,) [Hz], ascending
    shapes: object           # (ndof, n) mass-normalized, zero on fixed dofs
    ndof: int
    free_dofs: int
    parts: int
    backend: str             # the factorization used
    tie: object              # solve.tied.Tie: how the pairs were tied
    contact: list            # one dict per pair: rule, points, eps, law, coarse rule
    timings: dict            # stage -> seconds
    vtu: str = None          # the ParaView file written when output.vtu asks for it
    K: object = None         # with matrices=True: the model's stiffness [N/m] and mass [kg]
    M: object = None         # (sparse, every dof, before the contact), and its fixed dofs
    fixed: object = None

    def summary(self):
        """What ``transient modes --json`` prints, but for the total time."""
        return {"frequencies_hz": self.frequencies.tolist(), "ndof": self.ndof,
                "free_dofs": self.free_dofs, "backend": self.backend, "contact": self.contact,
                "tie": self.tie.kind, "held": self.tie.held, "held_of": self.tie.dofs,
                "timings": dict(self.timings)}


def dry_run(case, command="run", workers=0, scheduler=None, cache=None):
    """What a command would take on a case, checked and measured without doing it: the
    model built (dofs by part), each contact pair's fine rule and initial gaps (checked as
    the command would), the memory estimate of each process against ``limits.memory`` and,
    for a run, its steps, and the setup's time. Nothing of the case is factorized or written
    (this machine's calibration, when made, sets up a coarse case of its own in a child
    process).

    Parameters
    ----------
    case : Case
        From `load`.
    command : str
        "run", "modes" or "cea".
    workers, scheduler, cache
        Where the components path would reduce the parts, as `prepare` takes them.

    Returns
    -------
    dict
        ``parts`` (dofs, free dofs, cells), ``pairs`` (fine points, ``gap0``), ``memory``
        (``estimate_gb`` this process's, ``limit_gb``, ``largest_part`` the part whose
        reduction it counts, ``client`` whether it is a cluster's client's, ``worker_gb``
        the largest part's or piece's on a worker and ``worker_part`` which, ``budget_gb`` a
        worker's share of ``limits.memory`` on an embedded cluster (None where none),
        ``terms_gb`` what this process's estimate is made of, ``disk_gb`` the parts' bases
        in files of the temporary directory (the components path), and the reduction's
        ``method`` with ``auto``, why "auto" chose it), for a run ``steps``
        (``steps``, ``exact``: False where it is a bound, None where the setup's critical
        step sets it), ``setup_seconds`` (``low``, ``high``, ``source``: ``setups`` when
        estimated from the ``setups`` of its kind this machine has timed, else
        ``calibration``, from this machine's calibration, made now if there is none
        (transient.setuptimes); None with the setup-time log off).
    """
    from .dryrun import measure
    from .reduce.engine import used
    if command not in ("run", "modes", "cea"):
        raise CaseError("command line", "command", f"expected run, modes or cea, got "
                        f"'{command}'")
    case = on_cluster(case, Cluster.of(workers, scheduler))
    used(case, workers, scheduler, cache)
    return measure(case, command)


def modes(case, matrices=False):
    """Normal modes of a case, its contact pairs tied as ``solver.modes.tie`` says.

    Parameters
    ----------
    case : Case
        From `load`.
    matrices : bool
        Also return the model's sparse stiffness and mass.

    Returns
    -------
    NormalModes
        ``frequencies`` [Hz] and mass-normalized ``shapes`` (one column per mode on the
        model's dofs); with ``output.vtu`` the shapes are also written for ParaView.
    """
    from .solve.tied import case_modes
    if case.output.vtu:
        from .io.lock import check_writable
        check_writable(case.directory / case.output.vtu, "output.vtu")
    model, pairs, found, tie = case_modes(case)
    stage_times = {f"contact.{p.name}.{k}": v for p in pairs for k, v in p.timings.items()}
    vtu = None
    if case.output.vtu:
        from .mesh.meshfile import write_vtu
        vtu = str(case.directory / case.output.vtu)
        write_vtu(vtu, model.mesh(), point_data={
            f"mode_{i + 1:03d}_{f:.1f}Hz": found.shapes[:, i].reshape(-1, 3)
            for i, f in enumerate(found.frequencies)})
    asked = (model.K, model.M, model.fixed) if matrices else (None, None, None)
    return NormalModes(found.frequencies, found.shapes, model.ndof, int((~model.fixed).sum()),
                       len(model.parts), found.backend, tie, [_pair_summary(p) for p in pairs],
                       {**model.timings, **stage_times, **tie.timings, **found.timings},
                       vtu, *asked)


def _pair_summary(pair):
    out = {"pair": pair.name, "rule": pair.spec.rule, "regularized": pair.spec.regularized,
           "k": pair.k, "points": pair.rule.n_points, "area": pair.rule.area, "eps": pair.eps,
           "kept": pair.compat.kept(pair.eps) if pair.compat else None,
           "law": pair.spec.law.kind, "gap0": pair.gaps.meta() if pair.gaps else None}
    if pair.coarse is not None:
        out["coarse"] = {"m": len(pair.coarse.chosen), "energy_error": pair.coarse.energy_error,
                         "weighting": pair.coarse.weighting,
                         "setup_s": pair.timings["coarse_rule"]}
    return out


def cea(case, matrices=False, workers=0, scheduler=None, cache=None, on_part=None,
        on_stage=None):
    """Complex modes of a case at steady sliding with friction: which modes can squeal.

    The case's setup is linearized at its preload with the disc sliding; the complex modes
    come from QZ on the reduced model, or shift-invert Arnoldi on the full one
    (``solver.reduction.enabled = false``, the reference for small cases).

    Parameters
    ----------
    case : Case
        From `load`.
    matrices : bool
        Also return the linearized mass, damping and stiffness the modes solve.
    workers, scheduler, cache, on_part, on_stage
        Where the components path reduces its parts, and what is said meanwhile, as
        `prepare` says.

    Returns
    -------
    Analysis
        ``modes`` (``eigenvalues`` [1/s], ``frequency_hz``, ``real`` growth rates [1/s],
        ``damping_ratio``, ``unstable`` (growing faster than ``cea.threshold.growth_rate``),
        ``vectors`` in the system's coordinates), ``displacement(j)`` (mode j on the model's
        dofs), ``shapes`` (the modes described: the unstable ones, or all with
        ``cea.shapes = "all"``), ``fmax`` [Hz], ``ndof``, ``reduced``, ``stages`` [s],
        ``files`` (with ``output.vtu``: the CSV of the modes, then a VTU file and a ParaView
        collection per mode described), and with ``matrices=True``, ``matrices`` = (M, D,
        K), K complex where a material has a loss factor (its i eta K_m); ``summary()`` is
        what ``transient cea --json`` prints, but for the total time.

    Raises
    ------
    CaseError
        Any bad input, or output files that cannot be written or are not this package's
        (refused before the analysis).
    """
    from dataclasses import replace
    from .io import complex_modes
    from .stability.stage import analyse
    from .reduce.engine import engine_for
    complex_modes.check(case)
    case = on_cluster(case, Cluster.of(workers, scheduler))
    with engine_for(case, workers, scheduler, cache, on_part, on_stage) as parts:
        result = analyse(case, matrices=matrices, parts=parts)
    if complex_modes.names(case) is None:
        return result
    try:
        return replace(result, files=tuple(complex_modes.write(case, result)))
    except OSError as exc:
        raise CaseError(case.directory / case.output.vtu, "output.vtu",
                        f"cannot write: {exc}") from None


@dataclass(frozen=True)
class Campaign:
    """A campaign's rows and where they are (`sweep`)."""
    rows: list               # one dict per variant, in variant order: its values, its status
    variants: list           # campaign.variants.Variant: name, values, label()
    table: Path              # sweep.csv (beside it, sweep.json)


def sweep(case_path, parameters, out, mode="grid", kind="run", overrides=(), workers=2,
          scheduler=None, resume=False, progress=None, announce=None, command=None,
          cache=None):
    """A campaign: the case run (or analysed) for every variant of the parameters, on Dask.

    Parameters
    ----------
    case_path : str or Path
        The case file (each variant is loaded from it on a worker).
    parameters : sequence of str, or dict
        ``"KEY=VALUES"`` as the command line's ``--param`` (a TOML value or list, or
        ``start:stop:count``), or a dict of dotted key -> list of values.
    out : str or Path
        The campaign's folder: a history per variant, ``sweep.csv`` and ``sweep.json``.
    mode : str
        ``grid`` (every combination) or ``zip`` (the lists paired).
    kind : str
        ``run`` (a history per variant) or ``cea`` (complex modes per variant).
    overrides : sequence of str
        ``--set`` assignments applied to every variant, before its own.
    workers : int
        Worker processes of the embedded cluster.
    scheduler : str, optional
        The address of an existing Dask scheduler instead.
    resume : bool
        Keep the variants the folder holds complete, run the others.
    progress : callable, optional
        ``progress(done, total, failed)`` after each variant.
    announce : callable, optional
        ``announce(text)`` says where the Dask dashboard is.
    command : str, optional
        What the folder's lock says holds it.
    cache : str or Path, optional
        With ``solver.reduction.method = "components"``: the folder where each part's
        reduction is kept and read back, shared by the variants (a lining campaign reduces
        the pad for each modulus and the other parts once).

    Returns
    -------
    Campaign
        ``rows`` (one dict per variant), ``variants`` and ``table`` (the CSV's path).
    """
    from .campaign.campaign import sweep as run_campaign
    from .campaign.variants import make_variants, parse_parameter
    if isinstance(parameters, dict):
        parameters = [f"{k}={literal(list(v))}" for k, v in parameters.items()]
    variants = make_variants([parse_parameter(t) for t in parameters], mode)
    rows = run_campaign(case_path, variants, out, kind, list(overrides), workers, scheduler,
                        resume, progress, announce, command,
                        None if cache is None else str(Path(cache).resolve()))
    return Campaign(rows, variants, Path(out) / "sweep.csv")
