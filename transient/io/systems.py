"""The system a run integrates, stored in its history (`/system`) and read back: a resumed run
continues the very system it checkpointed, bit for bit, without redoing the setup (whose
factorizations and eigensolvers need not give the same last bits under another load or
thread count).

Every field of the frozen system is kept but the reduced basis T (ndof x n, the largest by
far; the history keeps it under /geometry when the field is stored) and what only the cea
reads (the loss, the factored rows' right factors):
arrays as datasets, sparse matrices and the contact set and critical step as groups, numbers
and names as attributes.
"""
import json
from dataclasses import fields

import numpy as np
import scipy.sparse as sp

from ..contact.contactset import ContactSet, FrictionSet
from ..dynamics.critical import CriticalStep
from ..dynamics.system import FullSystem, ReducedSystem
from ..errors import DamagedHistory
from .checksums import create

# the materials' loss is the cea's (a run integrates damp, which holds its share), as are the
# factored rows' right factors (its friction terms; the contact set is read back as rows)
SKIPPED = ("T", "loss", "base_damp", "shape_rows")
FRICTION_ARRAYS = ("speed", "m", "dm", "turn", "code", "v_eps", "table")

GROUP = "system"           # the history's group of the system integrated


def write_system(f, system):
    """Store system (ReducedSystem or FullSystem) under /system of the open HDF5 file f."""
    g = f.create_group(GROUP)
    g.attrs["kind"] = "reduced" if system.reduced else "full"
    for field in fields(system):
        if field.name not in SKIPPED:
            _write(g, field.name, getattr(system, field.name))


def read_system(f):
    """The system stored by write_system in the open HDF5 file f."""
    g = f[GROUP]
    cls = ReducedSystem if g.attrs["kind"] == "reduced" else FullSystem
    values = {}
    for field in fields(cls):
        if field.name not in SKIPPED:
            values[field.name] = _read(g, field.name)
    # the critical step evaluates the laws of the system's own contact set
    crit = values["critical"]
    values["critical"] = CriticalStep(crit["dt"], crit["kt_checked"], crit["rows"],
                                      values["contacts"], crit.get("omega_contact", 0.0),
                                      crit.get("omega_remainder", 0.0),
                                      crit.get("friction_dt", np.inf),
                                      crit.get("stick_dt", np.inf))
    return cls(**values)


def read_friction_law(f, pair):
    """(code, v_eps, table, tables, V) of a stored pair's points (contact.friction's law, as
    contact.friction.friction_powers takes it), without reading the rest of the system; None
    when the system has no friction."""
    node = f.get(f"{GROUP}/contacts")
    if node is None or "friction" not in node:
        return None
    a, b = _json(node, "slices")[pair]
    r = node["friction"]
    return (r["code"][a:b], r["v_eps"][a:b], r["table"][a:b], _read(r, "tables"),
            r["speed"][a:b])


def _write(g, name, value):
    if value is None:
        g.attrs[name] = "null"
    elif isinstance(value, np.ndarray):
        create(g, name, value)
    elif sp.issparse(value):
        s = g.create_group(name)
        s.attrs["type"], s.attrs["shape"] = "csr", value.shape
        A = sp.csr_matrix(value)
        for part in ("indptr", "indices", "data"):
            create(s, part, getattr(A, part))
    elif isinstance(value, ContactSet):
        s = g.create_group(name)
        s.attrs["type"] = "contacts"
        s.attrs["slices"] = json.dumps({k: [v.start, v.stop] for k, v in value.slices.items()})
        for part in ("gap0", "weights", "code", "params"):
            create(s, part, getattr(value, part))
        _write(s, "C", value.C)
        f = value.friction
        if f is not None:
            # the rows explicit, as C is (a factored set is read back as rows)
            r = s.create_group("friction")
            along, across = value.tangential()
            _write(r, "along", along)
            _write(r, "across", across)
            for part in FRICTION_ARRAYS:
                create(r, part, getattr(f, part))
            _write(r, "tables", tuple(f.tables))
    elif isinstance(value, CriticalStep):
        s = g.create_group(name)
        s.attrs["type"], s.attrs["dt"] = "critical", value.dt
        s.attrs["omega_contact"] = value.omega_contact
        s.attrs["omega_remainder"] = value.omega_remainder
        s.attrs["friction_dt"], s.attrs["stick_dt"] = value.friction_dt, value.stick_dt
        create(s, "kt_checked", value.kt_checked)
        create(s, "rows", value.rows)
    elif isinstance(value, tuple) and all(isinstance(v, np.ndarray) for v in value):
        s = g.create_group(name)
        s.attrs["type"], s.attrs["length"] = "arrays", len(value)
        for k, v in enumerate(value):
            create(s, str(k), v)
    else:
        # numbers, flags, and the sensor names (a tuple of strings)
        g.attrs[name] = json.dumps(list(value) if isinstance(value, tuple) else value)


def _read(g, name):
    if name not in g:
        value = _json(g, name)
        return tuple(value) if isinstance(value, list) else value
    node = g[name]
    kind = node.attrs.get("type") if hasattr(node, "keys") else None
    if kind is None:
        return node[()]
    if kind == "csr":
        return sp.csr_matrix((node["data"][()], node["indices"][()], node["indptr"][()]),
                             shape=tuple(node.attrs["shape"]))
    if kind == "contacts":
        pairs = _json(node, "slices")
        if not isinstance(pairs, dict):
            raise DamagedHistory(f"{node.name.lstrip('/')} attribute slices", "expected a table "
                                 "of pairs")
        slices = {k: slice(a, b) for k, (a, b) in pairs.items()}
        friction = None
        if "friction" in node:
            r = node["friction"]
            friction = FrictionSet(_read(r, "along"), _read(r, "across"),
                                   *(r[part][()] for part in FRICTION_ARRAYS),
                                   _read(r, "tables"))
        return ContactSet(_read(node, "C"), node["gap0"][()], node["weights"][()],
                          node["code"][()], node["params"][()], slices, friction=friction)
    if kind == "critical":
        return {"dt": float(node.attrs["dt"]), "kt_checked": node["kt_checked"][()],
                "rows": node["rows"][()],
                "omega_contact": float(node.attrs.get("omega_contact", 0.0)),
                "omega_remainder": float(node.attrs.get("omega_remainder", 0.0)),
                "friction_dt": float(node.attrs.get("friction_dt", np.inf)),
                "stick_dt": float(node.attrs.get("stick_dt", np.inf))}
    return tuple(node[str(k)][()] for k in range(int(node.attrs["length"])))


def _json(node, name):
    """The attribute name of node, stored as JSON text."""
    try:
        return json.loads(node.attrs[name])
    except (ValueError, TypeError, RecursionError):
        raise DamagedHistory(f"{node.name.lstrip('/')} attribute {name}", "not the JSON text "
                             "it was stored as") from None
