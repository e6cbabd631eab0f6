"""`transient export`: a history as time series that ParaView opens, XDMF (one .xdmf with its
.h5) or VTU (one .vtu per row and a .pvd collection naming them with their times).

One time series per kind of stored data:
- `contact_<pair>`: the pair's contact points as a point cloud with point data gap [m] and
  pressure [Pa] at each row, weight [m^2] and normal (fixed);
- `field`: the displacement [m] on the mesh of the model, from the stored state q: u[free] = q
  on a full model, u = T q on a reduced one, with the basis T the run stored next to q. The
  model is rebuilt from the case text the history keeps (quick: no factorization); it must give
  back the stored sensors, so a case or code changed since the run is caught.
"""
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import h5py
import meshio
import numpy as np

from ..mesh.meshfile import for_meshio_vtk
from .stored import open_history

FORMATS = ("xdmf", "vtu")
SENSOR_MATCH = 1e-6     # largest difference to the stored sensors, relative to their peak


@dataclass(frozen=True)
class Series:
    """A time series to write: fixed points and cells, point data read row by row."""
    name: str              # file name stem
    points: np.ndarray     # (n, 3) [m]
    cells: list            # [(meshio cell type, (ne, nen) node ids)]
    data: object           # (open history file, row) -> point data name -> array


class _XdmfWriter(meshio.xdmf.TimeSeriesWriter):
    """meshio's writer with its HDF5 file next to the XDMF file: meshio 5.3 creates it in the
    working directory, while the XDMF file names it relative to its own directory."""

    def __enter__(self):
        self.h5_filename = str(self.filename.with_suffix(".h5"))
        self.h5_file = h5py.File(self.h5_filename, "w")
        return self


def export(path, out=None, fmt="xdmf", every=1):
    """Write the contact and field series of a history for ParaView.

    Parameters
    ----------
    path : str or Path
        History written by `transient run`.
    out : str or Path, optional
        Directory of the files (default: next to the history, `<name>_export`).
    fmt : {'xdmf', 'vtu'}
    every : int
        Export one stored row in this many, and the last one.

    Returns
    -------
    list of Path
        The files to open in ParaView (.xdmf or .pvd), one per series.
    """
    stored = open_history(path)
    if fmt not in FORMATS:
        raise stored.error("--format", f"expected one of {', '.join(FORMATS)}, got '{fmt}'")
    if every < 1:
        raise stored.error("--every", f"expected an integer >= 1, got {every}")
    if stored.rows == 0:
        raise stored.error("", "no rows stored: nothing to export")
    series = [_contact_series(stored, pair) for pair in _contact_pairs(stored)]
    if "field/q" in stored.series:
        series.append(_field_series(stored))
    if not series:
        raise stored.error("", "nothing to export: run with output.field = true (the "
                           "displacement field) or output.contact = true (contact gaps and "
                           "pressures)")
    out = Path(out) if out else stored.path.with_name(stored.path.stem + "_export")
    out.mkdir(parents=True, exist_ok=True)
    rows = exported_rows(stored.rows, every)
    time = stored.time()
    write = _write_xdmf if fmt == "xdmf" else _write_pvd_series
    with stored.open() as f:
        return [write(out / s.name, s, f, rows, time) for s in series]


def exported_rows(n, every):
    """Rows 0, every, 2 every... and the last one."""
    # a step beyond the rows gives the first and the last (and stays an integer for arange)
    return np.union1d(np.arange(0, n, min(every, n)), [n - 1])


def _contact_pairs(stored):
    return [name.split("/")[1] for name in stored.series
            if name.startswith("contact/") and name.endswith("/gap")]


def _contact_series(stored, pair):
    fixed = stored.contact_geometry(pair)

    def data(f, row):
        return {"gap": f[f"contact/{pair}/gap"][row],
                "pressure": f[f"contact/{pair}/pressure"][row],
                "weight": fixed["weights"], "normal": fixed["normals"]}

    m = len(fixed["points"])
    return Series(f"contact_{pair}", fixed["points"], [("vertex", np.arange(m)[:, None])], data)


def _field_series(stored):
    """The displacement on the rebuilt model's mesh."""
    from ..model.model import build_model
    if len(stored.series["field/q"]) != 1:
        raise stored.error("field/q", f"damaged history: rows of shape "
                           f"{stored.series['field/q']}, expected one state vector per row")
    model = build_model(stored.case())
    width = stored.series["field/q"][0]
    if stored.meta.get("reduced"):
        T = stored.geometry("field/basis")
        if T is None:
            # a rebuilt basis would repeat the setup, and need not be the one integrated
            raise stored.error("geometry/field/basis", "the history keeps no basis of its "
                               "reduced model (written by an older version): run again")
        if T.ndim != 2 or len(T) != model.ndof:
            raise stored.error("geometry/field/basis", f"damaged history: shape {T.shape}, "
                               f"expected ({model.ndof}, reduced dofs)")
        T = np.asarray(T, dtype=float)
        columns = T.shape[1]

        def displacement(q):
            return T @ q
    else:
        free = model.free
        columns = len(free)

        def displacement(q):
            u = np.zeros(model.ndof)
            u[free] = q
            return u
    if columns != width:
        raise stored.error("field/q", f"the stored state has {width} values per row, the "
                           f"rebuilt model {columns}: the case or the code changed since the "
                           "run")
    _check_sensors(stored, model, displacement)
    mesh = model.mesh()

    def data(f, row):
        return {"displacement": displacement(f["field/q"][row]).reshape(-1, 3)}

    return Series("field", mesh.points, list(mesh.cells.items()), data)


def _check_sensors(stored, model, displacement):
    """The rebuilt model observes the stored sensor values from the stored state (first and
    last rows)."""
    names = [n for n in model.sensor_names if f"sensors/{n}" in stored.series]
    if not names:
        return
    rows = [0, stored.rows - 1]
    with stored.open() as f:
        stored_values = np.array([f[f"sensors/{n}"][: stored.rows] for n in names])
        rebuilt = np.array([model.sensors @ displacement(f["field/q"][k]) for k in rows]).T
    index = [model.sensor_names.index(n) for n in names]
    error = np.abs(rebuilt[index] - stored_values[:, rows]).max()
    peak = np.abs(stored_values).max()
    if error > SENSOR_MATCH * peak:
        raise stored.error("field/q", f"the rebuilt model misses the stored sensors by "
                           f"{error:.3g} (peak {peak:.3g}): the case or the code changed "
                           "since the run")


def _write_xdmf(stem, series, f, rows, time):
    path = stem.with_name(stem.name + ".xdmf")
    with _XdmfWriter(path) as writer:
        writer.write_points_cells(series.points, series.cells)
        for row in rows:
            writer.write_data(float(time[row]), point_data=series.data(f, row))
    return path


def _write_pvd_series(stem, series, f, rows, time):
    """One VTU file per row in directory `stem`, and the collection `stem`.pvd naming them."""
    stem.mkdir(exist_ok=True)
    entries = []
    for k, row in enumerate(rows):
        path = stem / f"{stem.name}_{k:06d}.vtu"
        mesh = meshio.Mesh(series.points, for_meshio_vtk(series.cells),
                           point_data=series.data(f, row))
        meshio.write(path, mesh, file_format="vtu")
        entries.append((float(time[row]), f"{stem.name}/{path.name}"))
    pvd = stem.with_name(stem.name + ".pvd")
    pvd.write_text(collection_xml(entries))
    return pvd


def collection_xml(entries):
    """A ParaView collection (.pvd) of (time [s], file path relative to the .pvd) entries."""
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    lines += [f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(name)}/>'
              for t, name in entries]
    lines += ["  </Collection>", "</VTKFile>", ""]
    return "\n".join(lines)
