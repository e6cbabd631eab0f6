"""`transient cea`'s files, when output.vtu = "DIR/NAME.vtu" asks for them.

- For ParaView, per mode kept (the unstable ones, or all with cea.shapes = "all"), NNN its row
  in the table: NAME_mode_NNN.vtu, the mesh with the real and imaginary parts of the mode's
  displacement (vectors u_real, u_imag [m]), their magnitude (|u_x|, |u_y|, |u_z|) and phase
  [deg]; and NAME_mode_NNN.pvd, a collection listing that one file at PHASES angles theta over
  a period, its time theta [rad], so that ParaView animates Re(u exp(i theta)) = u_real
  cos(theta) - u_imag sin(theta) (docs/commands.md#cea says how).
- For a spreadsheet, NAME_modes.csv: a row per mode of the table (frequency [Hz], real part
  [1/s], damping ratio, unstable), with the descriptors of the modes described.

Each shape is scaled by one complex number so that its largest displacement component is 1
(a unit of length, m), of phase zero: the VTU's field data say where (unit_node, 0-based, and
unit_direction, 0 1 2 for x y z) and give the mode's eigenvalue; the collection's comment says
it in words. A file of these names is replaced only when it is one of these (the VTU's field
data transient_cea_mode, the collection's comment, the CSV's header), and whole (under a
temporary name, then renamed); the mode files of an earlier analysis to the same NAME that
this one does not write again are removed, so that the folder holds one analysis.
"""
import csv
import io
import re
from pathlib import Path

import numpy as np

from ..files import whole as _whole
from .lock import check_writable
from ..errors import CaseError

PHASES = 24          # steps of the animation over a period (15 degrees)
BASE = ["mode", "frequency_hz", "real_per_s", "damping_ratio", "unstable"]
MARK = "transient cea"
VTU_MARK = "transient_cea_mode"      # the VTU's field data that names its mode
KEY = "output.vtu"


def names(case):
    """(folder, NAME) of the files output.vtu asks for, or None."""
    if not case.output.vtu:
        return None
    path = case.directory / case.output.vtu
    return path.parent, path.stem


def check(case):
    """Refuse (CaseError), before the analysis, output files that could not be written or
    are not this package's: the folder, output.vtu itself (not a directory), the CSV and
    every mode file of the NAME already there."""
    found = names(case)
    if found is None:
        return
    folder, stem = found
    check_writable(case.directory / case.output.vtu, KEY)
    csv_path = folder / f"{stem}_modes.csv"
    check_writable(csv_path, KEY)
    for path in [csv_path] + _mode_files(folder, stem):
        if path.exists() and not _ours(path):
            raise CaseError(path, KEY, f"exists and is not written by {MARK}: not overwritten "
                            "(choose another output.vtu)")


def write(case, analysis):
    """Write the files of an Analysis (stability.stage) of case: the list of their Paths,
    the CSV first, then each mode's VTU and collection."""
    folder, stem = names(case)
    csv_path = folder / f"{stem}_modes.csv"
    _whole(csv_path, lambda p: p.write_text(modes_csv(analysis), newline=""))
    written = [csv_path]
    mesh = analysis.model.mesh()
    for row in analysis.shapes:
        j = row["mode"] - 1
        u, unit = unit_shape(analysis.displacement(j))
        base = folder / f"{stem}_mode_{row['mode']:03d}"
        vtu, pvd = base.with_suffix(".vtu"), base.with_suffix(".pvd")
        note = _note(case, row, unit)
        _whole(vtu, lambda p: _write_vtu(p, mesh, u, unit, row, note))
        _whole(pvd, lambda p: p.write_text(_collection(vtu.name, note)))
        written += [vtu, pvd]
    for path in _mode_files(folder, stem):
        if path not in written and _ours(path):
            path.unlink()
    return written


def unit_shape(u):
    """(u / u_k, k) with k = argmax |u_k|: the largest displacement component 1, of zero
    phase."""
    k = int(np.argmax(np.abs(u)))
    v = u / u[k]
    v[k] = 1.0
    return v, k


def mode_rows(analysis):
    """The CSV's rows: a dict per mode of the table, its descriptors (flattened) when it is
    described, in the order of the table."""
    described = {row["mode"]: row for row in analysis.shapes}
    rows = []
    for i, m in enumerate(analysis.modes.table(), 1):
        row = {"mode": i, "frequency_hz": m["frequency_hz"], "real_per_s": m["real"],
               "damping_ratio": m["damping_ratio"], "unstable": m["unstable"]}
        if i in described:
            row.update(descriptors(described[i]))
        rows.append(row)
    return rows


def descriptors(row):
    """A described mode (stability.shapes.describe) as flat columns: each part's share of the
    kinetic energy, each rotating part's motion and nodal diameters, each still part's mode
    it resembles, the residual."""
    out = {f"energy_share_{p}": v for p, v in row["shares"].items()}
    for p, d in row.get("nodal_diameters", {}).items():
        out.update({f"{p}_motion": d["motion"], f"{p}_axial_share": d["axial_share"],
                    f"{p}_nodal_diameters": d["order"], f"{p}_order_share": d["share"]})
    for p, d in row.get("part_modes", {}).items():
        out.update({f"{p}_mode": d["mode"], f"{p}_mode_hz": d["frequency_hz"],
                    f"{p}_mac": d["mac"]})
    if "residual" in row:
        out["residual"] = row["residual"]
    return out


def modes_csv(analysis):
    """The CSV's text: BASE's columns, then the descriptors' in the order first met."""
    rows = mode_rows(analysis)
    columns = list(BASE)
    for row in rows:
        columns += [c for c in row if c not in columns]
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow([_cell(row.get(c)) for c in columns])
    return text.getvalue()


def _cell(value):
    """A CSV cell: '' for none, true/false, floats to the last digit."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value) if isinstance(value, float) else str(value)


def _write_vtu(path, mesh, u, unit, row, note):
    """The mode's VTU file: meshio's, with the note as a comment and the mode's numbers as
    field data (which meshio 5.3 reads but does not write) inserted before its grid."""
    from ..mesh.meshfile import write_vtu
    u3 = u.reshape(-1, 3)
    write_vtu(path, mesh, point_data={"u_real": u3.real, "u_imag": u3.imag,
                                      "u_magnitude": np.abs(u3),
                                      "u_phase_deg": np.degrees(np.angle(u3))})
    fields = [("Int64", VTU_MARK, row["mode"]), ("Float64", "frequency_hz", row["frequency_hz"]),
              ("Float64", "growth_rate_per_s", row["real"]),
              ("Float64", "damping_ratio", row["damping_ratio"]),
              ("Int64", "unstable", int(row["unstable"])), ("Int64", "unit_node", unit // 3),
              ("Int64", "unit_direction", unit % 3)]
    arrays = "".join(f'<DataArray type="{kind}" Name="{name}" NumberOfTuples="1" '
                     f'format="ascii">{value!r}</DataArray>\n' for kind, name, value in fields)
    text = path.read_bytes()
    grid = text.index(b"<UnstructuredGrid>") + len(b"<UnstructuredGrid>")
    path.write_bytes(text[:grid].replace(b"<UnstructuredGrid>", f"<!-- {note} -->\n"
                                         "<UnstructuredGrid>".encode())
                     + f"\n<FieldData>\n{arrays}</FieldData>".encode() + text[grid:])


def _note(case, row, unit):
    """The words on a mode's files: which mode, and how its shape is scaled."""
    return (f"{MARK}: mode {row['mode']} of {Path(case.path).name}, "
            f"{row['frequency_hz']:.6g} Hz, real part {row['real']:.6g} 1/s; u is scaled so "
            f"that its largest component, at node {unit // 3} along {'xyz'[unit % 3]}, is 1 "
            "with zero phase")


def _collection(vtu, note):
    """The .pvd of one mode: its VTU file at PHASES angles theta [rad] over a period."""
    from .export import collection_xml
    theta = 2 * np.pi * np.arange(PHASES) / PHASES
    text = collection_xml([(float(t), vtu) for t in theta])
    head, rest = text.split("\n", 1)
    return (f"{head}\n<!-- {note}. Each step's time is the phase angle theta [rad] of "
            f"Re(u exp(i theta)) = u_real cos(theta) - u_imag sin(theta). -->\n{rest}")


def _mode_files(folder, stem):
    """The mode files of NAME in the folder (VTU and collections), sorted."""
    pattern = re.compile(re.escape(stem) + r"_mode_\d+\.(vtu|pvd)")
    try:
        return sorted(p for p in Path(folder).iterdir() if pattern.fullmatch(p.name))
    except OSError:
        return []


def _ours(path):
    """Whether the file at path is one this module writes (by its first bytes)."""
    try:
        with open(path, "rb") as f:
            head = f.read(4096)
    except OSError:
        return False
    if path.suffix == ".csv":
        return head.startswith(",".join(BASE).encode())
    if path.suffix == ".pvd":
        return f"<!-- {MARK}: mode ".encode() in head
    return f'Name="{VTU_MARK}"'.encode() in head


