"""What a worker does with one variant: load it, run or analyse it, sum it up in a row.

Kinds: 'run' integrates the variant to its own history (the ordinary file `transient run`
writes, readable by `transient info`), then sums up its oscillation from the sensors (the
growth rate, the limit cycle's RMS and dominant frequency: studies.bench.oscillation);
'cea' computes its complex modes, written as JSON next to the histories with the case that
made them, and sums up the unstable ones; 'both' does the two from one setup (the complex
modes from the run's stages before its sampling: what `transient cea` analyses). A history
is written under the lock and the checks `transient run` makes (io.lock), or continued from
its checkpoint as `transient run --resume` does. A variant refused, or a run that aborts, is
a row with its reason: the campaign goes on. Each task first makes the settings a
`transient run` makes (transient.configure), on whatever cluster it lands.
"""
import json
import time
from pathlib import Path

from ..errors import CaseError
from ..settings import configure

KINDS = ("run", "cea", "both")


def run_variant(case_path, overrides, out, kind, built=None, resume=False, cache=None):
    """The row of one variant: status, seconds, the stages it ran and the summary numbers of
    its kind. out: its history (run, both) or its complex modes (cea). built: the first
    stages' results it shares with others (shared.Built), or None to build them. resume:
    continue its history (its complex modes, if any, are complete already). cache: the
    folder where the components path keeps its parts (reduce.engine.cached), or None."""
    configure()
    t0 = time.perf_counter()
    try:
        from ..case.loading import load
        case = load(case_path, overrides)
        parts = None
        if cache is not None:
            from ..reduce.engine import Engine
            parts = Engine(cache=Path(cache))
        if resume:
            row = _run(case, out, None, resume=True)
        else:
            row = {"run": _run, "cea": _cea, "both": _both}[kind](case, out, built, parts)
    except CaseError as exc:
        row = {"status": f"refused: {exc.key}: {exc.message}",
               "refusal": {"file": exc.path, "key": exc.key, "message": exc.message}}
    row["seconds"] = time.perf_counter() - t0
    # what its shared stages took to build, once for all the variants that share them
    row["shared_s"] = dict(built.seconds) if built is not None else {}
    return row


def build_shared(case_path, overrides, depth, built=None, kind="run"):
    """The first stages, to `depth`, of a group of variants that share them (shared.stage_key),
    built once, going on from a shallower group's `built`. A cea campaign's basis is made as
    its analyses make theirs, on the sampled rules' candidates: no points sampled for it."""
    from ..case.loading import load
    from ..stability.stage import analysed_case
    from ..shared import build_shared
    configure()
    case = load(case_path, overrides)
    return build_shared(analysed_case(case) if kind == "cea" else case, depth, built)


def _run(case, out, built, parts=None, on_setup=None, resume=False):
    from ..integration import run
    result = run(case, Path(out), resume=resume, progress=False, key="--out", built=built,
                 on_setup=on_setup, parts=parts)
    return {"status": result.status, "steps": result.steps, "dt": result.dt,
            "kernel_s": result.timings.get("kernel"), "energy_drift": result.energy_drift,
            "stages": sorted(result.stages), **_parts_reduced(result.meta), **summary(out)}


def _parts_reduced(meta):
    """The components path's parts the variant reduced itself, not read back from the
    campaign's cache ({} on the assembled path)."""
    stages = ((meta or {}).get("basis_timings") or {}).get("part_stages")
    if stages is None:
        return {}
    return {"parts_reduced": sorted(name for name, s in stages.items() if "cache" not in s)}


def summary(path):
    """The oscillation's numbers of a stored history (None where it has no sensor)."""
    import h5py
    from ..studies.bench import oscillation
    with h5py.File(path, "r") as f:
        series = {"time": f["time"][()]}
        if "sensors" in f:
            series.update({f"sensors/{k}": f["sensors"][k][()] for k in f["sensors"]})
    if not any(k.startswith("sensors/") for k in series):
        return {"growth_rate": None, "cycle_rms": None, "cycle_frequency": None}
    numbers, _ = oscillation(series)
    return {k: (None if v != v else v) for k, v in numbers.items()}        # NaN: None


def _cea(case, out, built, parts=None):
    from ..stability.stage import analyse
    result = analyse(case, built=built, parts=parts)
    return {"status": "complete", "stages": sorted(result.stages),
            **_parts_reduced(result.meta), **_modes_written(result, case, out)}


def _both(case, out, built, parts=None):
    """The run, and the complex modes from its setup before the time integration."""
    from ..stability.stage import analysis_of
    modes = Path(out).with_suffix(".json")
    found = {}

    def analyse(setup):
        found.update(_modes_written(analysis_of(case, setup.unsampled or setup), case, modes))
    return {**_run(case, out, built, parts, analyse), **found}


def _modes_written(analysis, case, path):
    """The complex modes of an Analysis of case written as JSON at path, with what made them
    (the case's text, path and overrides: a resumed campaign compares them with its variant's,
    as a history's); their summary. The file is replaced whole (a killed writer leaves the
    old one or none), and only if it is absent or the modes of a campaign."""
    from .. import __version__
    from .folder import MARK, modes_file, write_whole
    path = Path(path)
    if path.exists() and path.stat().st_size and modes_file(path) is None:
        raise CaseError(path, "--out", "exists and is not complex modes written by transient "
                        "sweep: not overwritten")
    from ..stability.branches import observed, shapes_record
    modes = analysis.modes.table()
    # the shapes at a few hundred nodes: what `plot sweep` links the variants' modes by
    text = json.dumps({"written_by": MARK, "version": __version__, "status": "complete",
                       "case": case.text, "case_path": str(Path(case.path).resolve()),
                       "overrides": list(case.overrides), "modes": modes,
                       "growth_rate_threshold": analysis.modes.threshold,
                       "shapes": shapes_record(*observed(analysis)),
                       "ndof": analysis.ndof, "reduced": analysis.reduced})
    write_whole(path, text)
    return cea_summary(modes)


def cea_summary(modes):
    """The unstable modes of a table of complex modes: their count, the strongest one's real
    part and frequency (None without), and each one's (frequency, real part)."""
    unstable = [m for m in modes if m["unstable"]]
    strongest = max(unstable, key=lambda m: m["real"]) if unstable else None
    return {"unstable": len(unstable), "max_real": strongest["real"] if strongest else None,
            "frequency_hz": strongest["frequency_hz"] if strongest else None,
            "unstable_modes": [[m["frequency_hz"], m["real"]] for m in unstable]}
