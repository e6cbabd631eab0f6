"""The data lines of *NODE, *ELEMENT, *NSET and *ELSET keywords as labels, coordinates,
connectivity and set definitions."""
from dataclasses import dataclass

import numpy as np

from ..elements import ELEMENTS
from .types import ACCEPTED, SKIPPED, classify


@dataclass(frozen=True)
class Nodes:
    """Nodes of a list of *NODE keywords: labels (n,), coordinates (n, 3) and, per node, the
    keyword (index into `keywords`) and data row that defines it."""
    labels: np.ndarray
    points: np.ndarray
    keyword: np.ndarray
    row: np.ndarray
    keywords: tuple


@dataclass(frozen=True)
class Block:
    """The elements of one *ELEMENT keyword: its Abaqus type, kind and meshio cell type
    (types.classify), labels (m,), node labels (m, nen) ((m, 0) for a skipped type) and the
    data row where each element ends."""
    abaqus_type: str
    kind: str
    ctype: str
    labels: np.ndarray
    conn: np.ndarray
    rows: np.ndarray
    keyword: object


@dataclass(frozen=True)
class SetDef:
    """One definition of a node or element set: a *NSET or *ELSET keyword (explicit), or the
    NSET= of a *NODE or the ELSET= of an *ELEMENT.

    labels : labels listed, with the data row of each (rows).
    ranges : (first, last, step, row) of GENERATE lines.
    names : (name as written, row) of the sets it includes.
    instance : the INSTANCE= parameter (an assembly's set of an instance's labels), or None.
    elset : *NSET's ELSET= parameter: the nodes of that element set, or None.
    """
    keyword: object
    labels: np.ndarray
    rows: np.ndarray
    ranges: tuple = ()
    names: tuple = ()
    instance: str = None
    elset: str = None
    internal: bool = False
    explicit: bool = True


def parse_nodes(keywords):
    """Nodes of *NODE keywords; SYSTEM=C gives r, theta [deg], z."""
    labels, points, owner, rows = [], [], [], []
    for k, kw in enumerate(keywords):
        system = (kw.get("SYSTEM") or "R").upper()
        if system not in ("R", "C"):
            raise kw.error(f"SYSTEM={system} not read here: expected R (x, y, z) or C "
                           "(r, theta, z)")
        xyz = np.zeros((len(kw.data), 3))
        for r, row in enumerate(kw.data):
            try:
                labels.append(int(row[0]))
                values = [float(v) if v else 0.0 for v in row[1:4]]
            except (ValueError, IndexError):
                raise kw.error(f"expected a node label and its coordinates, got "
                               f"{', '.join(row)}", r) from None
            xyz[r, :len(values)] = values
        if system == "C":
            theta = np.radians(xyz[:, 1])
            xyz = np.column_stack([xyz[:, 0] * np.cos(theta), xyz[:, 0] * np.sin(theta),
                                   xyz[:, 2]])
        points.append(xyz)
        owner.append(np.full(len(kw.data), k))
        rows.append(np.arange(len(kw.data)))
    cat = (lambda a, dtype: np.concatenate(a).astype(dtype) if a else np.zeros(0, dtype))
    return Nodes(np.array(labels, dtype=np.int64),
                 np.vstack(points) if points else np.zeros((0, 3)),
                 cat(owner, np.int64), cat(rows, np.int64), tuple(keywords))


def parse_elements(keyword):
    """The Block of one *ELEMENT keyword. An element's labels may run over several data
    lines (C3D20's 21 numbers do in most decks)."""
    abaqus_type = (keyword.get("TYPE") or "").upper()
    if not abaqus_type:
        raise keyword.error("expected TYPE=, the element type")
    kind, ctype = classify(abaqus_type)
    if kind is None:
        raise keyword.error(f"element type {abaqus_type} cannot be used: expected solids "
                            f"{ACCEPTED} (shells, membranes, beams, springs and masses are "
                            "left out with a note)")
    nen = 0 if kind == SKIPPED else ELEMENTS[ctype].nen
    records, rows, pending = [], [], []
    for r, row in enumerate(keyword.data):
        try:
            pending.extend(int(v) for v in row if v)
        except ValueError:
            raise keyword.error(f"expected an element label and {nen or 'its'} node labels, "
                                f"got {', '.join(row)}", r) from None
        if kind == SKIPPED:
            records.append(pending[:1])
            rows.append(r)
            pending = []
        elif len(pending) >= nen + 1:
            if len(pending) > nen + 1:
                raise keyword.error(f"element {pending[0]}: {len(pending) - 1} node labels, "
                                    f"expected {nen} for {abaqus_type}", r)
            records.append(pending)
            rows.append(r)
            pending = []
    if pending:
        raise keyword.error(f"element {pending[0]}: {len(pending) - 1} node labels, expected "
                            f"{nen} for {abaqus_type}", len(keyword.data) - 1)
    table = np.array(records, dtype=np.int64).reshape(-1, nen + 1)
    return Block(abaqus_type, kind, ctype, table[:, 0], table[:, 1:],
                 np.array(rows, dtype=np.int64), keyword)


def set_name(keyword, param, what):
    name = keyword.get(param)
    if not name:
        raise keyword.error(f"expected {param}=NAME: a {what} set without a name")
    return name


def parse_set(keyword, param, what):
    """(name, SetDef) of a *NSET (param 'NSET') or *ELSET ('ELSET'): labels, GENERATE ranges
    'first, last[, step]', names of other sets."""
    name = set_name(keyword, param, what)
    labels, rows, ranges, names = [], [], [], []
    generate = "GENERATE" in keyword.params
    for r, row in enumerate(keyword.data):
        fields = [f for f in row if f]
        if generate:
            ranges.append(_range(keyword, fields, r) + (r,))
            continue
        for f in fields:
            try:
                labels.append(int(f))
                rows.append(r)
            except ValueError:
                names.append((f, r))
    elset = keyword.get("ELSET") if param == "NSET" else None
    return name, SetDef(keyword, np.array(labels, dtype=np.int64), np.array(rows, np.int64),
                        tuple(ranges), tuple(names), keyword.get("INSTANCE"), elset,
                        "INTERNAL" in keyword.params)


def _range(keyword, fields, row):
    try:
        values = [int(f) for f in fields]
    except ValueError:
        values = []
    if len(values) == 2:
        values.append(1)
    if len(values) != 3 or values[2] < 1 or values[1] < values[0]:
        raise keyword.error(f"GENERATE: expected first, last, increment with last >= first "
                            f"and increment >= 1, got {', '.join(fields)}", row)
    return tuple(values)


def labels_set(keyword, name, labels, rows):
    """The SetDef that a *NODE's NSET= or an *ELEMENT's ELSET= parameter makes."""
    return name, SetDef(keyword, np.asarray(labels, np.int64), np.asarray(rows, np.int64),
                        explicit=False)
