"""The public API on a run's results: `transient.history` (a history opened for reading, what
every picture of a history draws from), `summary` (what `transient info` prints), `export`
(the history as time series for ParaView) and `modal_growth` (the run read mode by mode
against its complex modes).

The readers (h5py, meshio) are imported by the functions, so that `import transient` stays
light."""
from .errors import CaseError


def history(path):
    """A history written by `run`, opened for reading.

    The series stay in the file until read, so that a long run's history is opened at once;
    a history still being written (or stopped early) reads as its complete rows.

    Parameters
    ----------
    path : str or Path
        The HDF5 file.

    Returns
    -------
    Stored
        ``path``, ``rows`` (complete rows), ``series`` (name -> shape of one row, e.g.
        ``"sensors/tip": ()``), ``meta`` (the run's attributes, ``status`` included);
        ``time()`` [s] and ``read(name)`` give the arrays, ``case()`` the case the run was
        made with.

    Raises
    ------
    CaseError
        A missing file, or one that is not a history of this package (or is damaged).
    """
    from .io.stored import open_history
    return open_history(path)


def summary(path):
    """What a history holds, as ``transient info --json`` prints it.

    Parameters
    ----------
    path : str or Path
        The HDF5 file.

    Returns
    -------
    dict
        ``path``, ``file_size`` [bytes], ``status``, ``steps`` (rows), ``t_end`` [s],
        ``energy_drift``, ``timings`` [s], ``series`` (name -> shape of one row) and ``meta``
        (the run's other attributes, but for the case's text): plain values that
        ``json.dumps`` takes.

    Raises
    ------
    CaseError
        A missing file, or one that is not a history of this package (or is damaged).
    """
    from .io.stored import read_summary
    return read_summary(path)


def export(path, out=None, format="xdmf", every=1):
    """Write a history's contact points and displacement field as time series for ParaView.

    One series per stored contact pair (its points with their gap [m] and pressure [Pa]) and,
    when the run stored its state (``output.field``), the displacement [m] on the mesh of the
    model, rebuilt from the case the history keeps.

    Parameters
    ----------
    path : str or Path
        A history written by `run`.
    out : str or Path, optional
        The files' folder; by default ``<name>_export`` next to the history.
    format : {'xdmf', 'vtu'}
        ``xdmf``: one ``.xdmf`` (and its ``.h5``) per series; ``vtu``: one ``.vtu`` per row
        and a ``.pvd`` collection naming them with their times.
    every : int
        Write one stored row in this many, and the last one.

    Returns
    -------
    list of Path
        The files to open in ParaView (``.xdmf`` or ``.pvd``), one per series.

    Raises
    ------
    CaseError
        A bad history or option, nothing stored to export, or a folder that cannot be
        written.
    """
    from .io.export import export as write
    try:
        return write(path, out, format, every)
    except OSError as exc:
        raise CaseError(out or path, "--out", f"cannot write: {exc}") from None


def modal_growth(path, cea=None, window=None, tolerance=None):
    """A run's motion projected on the complex modes of its system linearized at its
    preload: each mode's amplitude in time and its growth rate fitted over the linear phase,
    beside the CEA's real part.

    The run's reduced state about its equilibrium, z = [q - q_eq; v] (v from central
    differences of the stored q, taken exactly for each mode), gives each mode's amplitude
    a_k = y_k^H B z / (y_k^H B x_k) with y_k, x_k its left and right eigenvectors, a pure
    exponential of rate Re lambda_k in a linear motion. The growth is the least-squares slope
    of log|a_k| over the longest window from the free motion's start (the loads' last change)
    where log a_k stays within ``tolerance`` of a line, within the linear phase (until the
    largest amplitude reaches a tenth of its peak); a mode that does not stand out for ten of
    its periods is marked not excited. The theory is in `transient.stability.growth`.

    Parameters
    ----------
    path : str or Path
        A history written by `run` with ``output.field = true`` (a reduced model's), its
        rows at least four a period of the band's top (``output.every``).
    cea : Analysis or ComplexModes, optional
        The CEA of the same case (`cea`'s, or its ``modes``); by default made here from the
        case the history keeps (its whole setup, minutes on a large model).
    window : (float, float), optional
        The times [s] fitted, whole, by every mode, instead of the linear phase found.
    tolerance : float, optional
        The RMS deviation of log a_k (log amplitude and phase) from its line that a fit
        admits; default ``transient.stability.growth.LOG_RMS``.

    Returns
    -------
    ModalGrowth
        Per mode of the run's linearization in the band (imaginary part >= 0, by
        frequency): ``eigenvalues`` [1/s], ``frequency_hz``, ``cea`` (the CEA's eigenvalue
        paired one to one by the nearest), ``growth`` [1/s] and its window's
        ``resolution`` [1/s] (the slowest rate it tells from neutral), ``rms``, ``windows``
        [s], ``excited``, ``resolved``, ``difference`` (relative to the CEA's real part) and
        the ``amplitudes`` |a_k(t)| [sqrt(kg) m] at ``time`` [s]; ``table()`` gives one dict
        per mode.

    Raises
    ------
    CaseError
        A history without the state, of a full model, with rows too sparse for the band or
        unevenly spaced, or whose loads change to its end (without a window).
    """
    from .io.stored import open_history
    from .stability.growth import LOG_RMS, history_growth
    stored = open_history(path)
    if window is not None and not (len(window) == 2 and window[0] < window[1]):
        raise CaseError(path, "window", f"expected (t0, t1) with t0 < t1, got {window}")
    if cea is None:
        from .stability.stage import analyse

        def cea(case):
            return analyse(case).modes
    return history_growth(stored, cea if callable(cea) else getattr(cea, "modes", cea), window,
                          LOG_RMS if tolerance is None else tolerance)
