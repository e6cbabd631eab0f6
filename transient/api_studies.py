"""The public API's studies of a case: `transient.bench` (error against run time for a sweep of
contact rules) and `compare_modes` (two modal models of one structure, their modes paired and
their transfer functions, the paper's figure 11)."""
import tempfile
from dataclasses import dataclass
from pathlib import Path

from .errors import CaseError


@dataclass(frozen=True)
class Bench:
    """A bench's rows, its target row and its files (`bench`)."""
    rows: list               # one dict per variant, the reference first
    target: dict             # the best row that meets the target, or None
    files: list              # bench.csv, bench.json and bench.png (none without a folder)

    def summary(self):
        """What ``transient bench --json`` prints."""
        return {"rows": self.rows, "target": self.target}


def bench(case, pair=None, eps=(1e-6, 1e-4, 1e-3, 1e-2), points=None, t_end=None,
          tolerances=(3e-2, 1e-2, 3e-3), reference="fine", cycle_from=None, out=None,
          progress=None):
    """Error against run time of a case for a sweep of contact rules on one pair.

    Each variant (the reference; the fine rule regularized at each eps; the centre rule,
    plain and regularized; the greedy rule at several point counts; the sampled rule at
    each tolerance) is set up and integrated over the same time, then compared with the
    reference on its sensor histories, its preload, its largest pressure and its
    contact-linearized frequencies (and with friction, its growth rate and limit cycle).

    Parameters
    ----------
    case : Case
        From `load`; each variant is loaded again from its file and overrides.
    pair : str, optional
        The pair whose rule varies; by default the case's first.
    eps : sequence of float
        The regularized fine rule's eps.
    points : sequence of int, optional
        The greedy rule's point counts, 0 for the rank of the kept shapes; by default that
        rank r, then r / 2, r / 4, 4 r and 10 r (those below the fine rule's count).
    t_end : float, optional
        The time integrated [s]; by default the case's ``solver.t_end``.
    tolerances : sequence of float
        The sampled rule's tolerances (regularized at the case's eps).
    reference : {'fine', 'case'}
        The fine rule, or the case's own rule at half its step (a saturated squeal, whose
        implicit steps on the fine rule cost too much).
    cycle_from : float, optional
        With friction: the start of the limit cycle's window [s]; by default the run's last
        quarter.
    out : str or Path, optional
        A folder to write ``bench.csv``, ``bench.json`` and ``bench.png`` in, checked
        writable before the first variant.
    progress : callable, optional
        ``progress(row)`` as each variant's row is made.

    Returns
    -------
    Bench
        ``rows`` (one dict per variant, the reference first: ``label``, ``points``,
        ``setup_s`` and ``kernel_s`` [s], ``error_rms``, ``frequency_error``, ``status``...),
        ``target`` (the fastest regularized coarse row within 1% of the reference at a third
        or less of its kernel time, or None) and ``files``; ``summary()`` is what
        ``transient bench --json`` prints.
    """
    from .studies.bench import bench as sweep_rules
    from .studies.bench import checked_pair, target, write
    pair = checked_pair(case, pair, reference, cycle_from, t_end)
    if out is not None:
        out = _writable_folder(out)
    rows = sweep_rules(case.path, case.overrides, pair, list(eps),
                       None if points is None else list(points), t_end, progress,
                       list(tolerances), reference, cycle_from)
    return Bench(rows, target(rows), [] if out is None else write(rows, out))


def _writable_folder(path):
    """The folder at path, made if missing and checked writable."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=path).close()
    except OSError as exc:
        raise CaseError(path, "--out", f"cannot write: {exc.strerror or exc}") from None
    return path


def compare_modes(case, against, sensor_in, sensor_out, damping=0.01, fmax=None):
    """Two modal models of one structure compared, with their contact tied as each case's
    ``solver.modes.tie`` says: each mode of the first paired with a mode of the second, the
    frequency shifts, and the transfer function between two sensors.

    Modes are paired by MAC when both cases make the same model (the same meshes and
    materials, other contact settings), else by order.

    Parameters
    ----------
    case, against : Case
        From `load`: the first model and the one compared with it.
    sensor_in : str
        The sensor where the force is applied (along its direction).
    sensor_out : str
        The sensor whose displacement responds.
    damping : float
        The transfer functions' modal damping ratio, in [0, 1).
    fmax : float, optional
        The transfer functions' highest frequency [Hz]; by default just above the highest
        mode.

    Returns
    -------
    ModalComparison
        ``frequencies`` (each model's [Hz]), ``partner`` (each first mode's partner in the
        second, -1 for none), ``mac``, ``shifts`` (100 (f_partner / f - 1) [%]),
        ``by_order`` (the shifts mode by mode [%]), ``f`` [Hz] and ``transfer`` (each
        model's receptance [m/N]), ``ties`` and ``pairs`` (each model's contact).
    """
    sensors = list(case.sensors)
    for key, name in (("--input", sensor_in), ("--output", sensor_out)):
        if name not in sensors:
            raise CaseError(case.path, key, f"expected a sensor of the case ("
                            f"{', '.join(sensors) or 'none'}), got '{name}'")
    if not 0 <= damping < 1:
        raise CaseError(case.path, "--damping", f"expected a ratio in [0, 1), got {damping}")
    if fmax is not None and not fmax > 0:
        raise CaseError(case.path, "--fmax", f"expected a frequency > 0 [Hz], got {fmax}")
    from .studies.modal import compare
    return compare(case, against, sensor_in, sensor_out, damping, fmax)
