"""The public API on a run's results: `transient.history` (a history opened for reading, what
every picture of a history draws from), `summary` (what `transient info` prints) and `export`
(the history as time series for ParaView).

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
