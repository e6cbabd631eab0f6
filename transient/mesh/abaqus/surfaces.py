"""*SURFACE definitions resolved to faces: TYPE=ELEMENT lines 'ELSET or LABEL, Sn' (face n
of each solid, types.FACES), a line without a face (the solids' faces on the boundary, or
the 2-D elements themselves), and TYPE=NODE lines (a node set)."""
import re
from dataclasses import dataclass, field

import numpy as np

from ..elements import FACE_TYPE_OF
from .types import FACE, FACES, SOLID

_FACE_ID = re.compile(r"^S(\d+)$")
_TWO_D_SIDES = ("", "SPOS", "SNEG")


@dataclass
class Surface:
    """faces: face type -> [(nf, nfn) global node ids, outward]; free: [global ids of solid
    elements whose faces on the boundary belong]; two_d: [global ids of 2-D elements, whose
    own face belongs]; nodes: [global node ids] of a TYPE=NODE surface."""
    faces: dict = field(default_factory=dict)
    free: list = field(default_factory=list)
    two_d: list = field(default_factory=list)
    nodes: list = field(default_factory=list)


def read_surface(resolver, body, keyword):
    """The Surface of a *SURFACE keyword of a body, or None for a kind not read here (an
    analytical surface: TYPE=SEGMENTS, CYLINDER, REVOLUTION)."""
    kind = (keyword.get("TYPE") or "ELEMENT").upper()
    out = Surface()
    if kind == "NODE":
        for r, row in enumerate(keyword.data):
            if row and row[0]:
                out.nodes.append(resolver.reference("node", body, row[0], keyword, r))
        return out
    if kind != "ELEMENT" or "COMBINE" in keyword.params:
        return None
    model = resolver.model
    for r, row in enumerate(keyword.data):
        if not row or not row[0]:
            continue
        side = row[1].upper() if len(row) > 1 else ""
        elems = resolver.reference("element", body, row[0], keyword, r)
        for b in np.unique(model.block_of[elems]):
            blk = model.blocks[b]
            mine = elems[model.block_of[elems] == b]
            rows = model.row_of[mine]
            if blk.kind == SOLID:
                _solid_faces(out, model, b, rows, side, mine, keyword, r)
            elif blk.kind == FACE and side in _TWO_D_SIDES:
                out.two_d.append(mine)
            else:
                expected = ("SPOS, SNEG or no face" if blk.kind == FACE
                            else "solid or 2-D elements")
                raise keyword.error(f"{blk.abaqus_type} element {blk.labels[rows[0]]}"
                                    + (f", face {side}" if side else "")
                                    + f": expected {expected}", r)
    return out


def _solid_faces(out, model, b, rows, side, elems, keyword, r):
    blk = model.blocks[b]
    if not side:
        out.free.append(elems)
        return
    faces = FACES[blk.ctype]
    match = _FACE_ID.match(side)
    k = int(match.group(1)) if match else 0
    if not 1 <= k <= len(faces):
        raise keyword.error(f"face {side} of {blk.abaqus_type} element {blk.labels[rows[0]]}: "
                            f"expected S1 to S{len(faces)} (the element's faces)", r)
    local = np.array(faces[k - 1])
    ftype = FACE_TYPE_OF[len(local)]
    out.faces.setdefault(ftype, []).append(model.conn[b][rows][:, local])

