"""The Mesh of an Abaqus deck: its solids as cells, its node sets, its element sets as cell
sets (solids) and face sets (2-D elements on the solids' boundary), its surfaces as face or
node sets, and each instance as a cell set of its name."""
from collections import Counter

import numpy as np

from ..elements import ELEMENTS, VOLUME_TYPES
from ..fileerror import MeshFileError
from ..mesh import Mesh, boundary_faces, face_key, face_nodes
from ..selections import find_set
from .bodies import build_model
from .scopes import read_deck_structure
from .sets import Resolver
from .surfaces import read_surface
from .types import ACCEPTED, FACE, SKIPPED, SOLID


def read_abaqus(path):
    """(Mesh, notes) of the deck at path; notes: lines on what was left out of it.

    Names are those of the deck, with the spelling of their first definition; an instance's
    sets and surfaces are 'INSTANCE.NAME' and the assembly's 'NAME'. Internal sets (INTERNAL,
    as Abaqus/CAE marks the sets behind its surfaces) are not kept. Nodes that no solid uses
    are dropped, and the sets left empty.
    """
    deck = read_deck_structure(path)
    model = build_model(deck)
    cells, cell_of = _solids(model)
    if not cells:
        hint = (" (the deck defines parts but no *INSTANCE of them)"
                if deck.parts and not deck.instances else "")
        raise MeshFileError(path, f"no solid elements: expected {ACCEPTED}{hint}")
    solid = Mesh(model.points, cells)
    boundary = _Boundary(solid)
    two_d = _two_d_faces(model, boundary)
    resolver = Resolver(model)
    sets = _Sets(model, cell_of, boundary, two_d)
    notes = []
    for body in model.bodies:
        for key, defs in body.nsets.items():
            if not any(d.internal for _, d in defs):
                sets.add_nodes(_name(body, key), resolver.nodes(body, key))
        for key, defs in body.elsets.items():
            if not any(d.internal for _, d in defs):
                sets.add_elements(_name(body, key), resolver.elements(body, key), defs)
        for key, defs in body.surfaces.items():
            for name, keyword in defs:
                surface = read_surface(resolver, body, keyword)
                if surface is None:
                    notes.append(f"surface {body.prefix}{name} not read ({keyword.text}: "
                                 "an analytical or combined surface)")
                else:
                    sets.add_surface(_name(body, key), surface, keyword)
    for b, body in enumerate(model.bodies):
        if body.name and find_set(sets.cells, body.name) is None:
            sets.add_instance(body.name, b)
    notes += _left_out(model, _used(sets.used), _structural(resolver))
    return sets.mesh(model.points, cells), notes


def _used(parts):
    return np.unique(np.concatenate(parts)) if parts else np.zeros(0, np.int64)


def _structural(resolver):
    """Global ids of the elements under a shell, membrane or solid section: structure of the
    deck's model (a section naming a set not defined here gives none)."""
    ids = []
    for body in resolver.model.bodies:
        for name, keyword in body.sections:
            target, rest = resolver.split(body, name)
            if rest.upper() in target.elsets:
                ids.append(resolver.elements(target, rest.upper()))
    return _used(ids)


def _name(body, key):
    """A set's name in the mesh: its instance's prefix and the spelling of its first
    definition (node sets, then element sets, then surfaces)."""
    for table in (body.nsets, body.elsets, body.surfaces):
        if key in table:
            return body.prefix + table[key][0][0]
    raise KeyError(key)


def _solids(model):
    """Cells by type (global node ids) and, per block, the offset of its rows in its type's
    cells (-1 for blocks that are not solids)."""
    cells, offset = {}, np.full(len(model.blocks), -1, dtype=np.int64)
    for b, blk in enumerate(model.blocks):
        if blk.kind == SOLID and len(blk.labels):
            parts = cells.setdefault(blk.ctype, [])
            offset[b] = sum(len(c) for c in parts)
            parts.append(model.conn[b])
    return {t: np.vstack(cells[t]) for t in VOLUME_TYPES if t in cells}, offset


class _Boundary:
    """The solids' boundary faces, outward, with a lookup by their corner nodes, found when
    first asked for (a deck without 2-D elements or faceless surface lines never does)."""

    def __init__(self, mesh):
        self.mesh = mesh
        self.index = None

    @property
    def faces(self):
        if self.index is None:
            self._find()
        return self._faces

    def _find(self):
        self._faces = boundary_faces(self.mesh)
        self.index = {ft: dict(zip(map(tuple, face_key(f, ELEMENTS[ft].n_corners).tolist()),
                                   range(len(f)))) for ft, f in self._faces.items()}

    def match(self, faces, ftype):
        """(index of each face among the boundary faces of its type or -1)."""
        if self.index is None:
            self._find()
        table = self.index.get(ftype, {})
        keys = map(tuple, face_key(faces, ELEMENTS[ftype].n_corners).tolist())
        return np.array([table.get(k, -1) for k in keys], dtype=np.int64)


def _two_d_faces(model, boundary):
    """Per global element id of a 2-D element: (face type, index of its boundary face or -1)
    as a dict of arrays: face type -> (global ids (m,), boundary index (m,))."""
    out = {}
    for b, blk in enumerate(model.blocks):
        if blk.kind == FACE and len(blk.labels):
            ids, idx = out.setdefault(blk.ctype, ([], []))
            ids.append(model.first[b] + np.arange(len(blk.labels)))
            idx.append(boundary.match(model.conn[b], blk.ctype))
    return {ft: (np.concatenate(i), np.concatenate(x)) for ft, (i, x) in out.items()}


def _left_out(model, used, structural):
    """One note on the elements left out of the model, if any: every element that is not a
    solid but a 2-D one that only makes faces of a set (on the solids' boundary, under no
    structural section: the faces gmsh and meshio write)."""
    counts, faces_too = Counter(), set()
    for b, blk in enumerate(model.blocks):
        ids = model.first[b] + np.arange(len(blk.labels))
        if blk.kind == SKIPPED:
            counts[blk.abaqus_type] += len(ids)
        elif blk.kind == FACE:
            structure = np.isin(ids, structural)
            left = structure | ~np.isin(ids, used)
            counts[blk.abaqus_type] += int(left.sum())
            if (structure & np.isin(ids, used)).any():
                faces_too.add(blk.abaqus_type)
    counts = {t: n for t, n in counts.items() if n}
    if not counts:
        return []
    listed = ", ".join(f"{n} {t}" for t, n in sorted(counts.items()))
    total = sum(counts.values())
    note = ("1 element that is not a solid is" if total == 1
            else f"{total} elements that are not solids are")
    note += f" left out of the model ({listed})"
    if faces_too:
        note += (f"; the {', '.join(sorted(faces_too))} on the solids' boundary still give "
                 "their sets' faces")
    return [note]


class _Sets:
    """The node, face and cell sets of the mesh being made, in global node ids."""

    def __init__(self, model, cell_of, boundary, two_d):
        self.model, self.cell_of, self.boundary, self.two_d = model, cell_of, boundary, two_d
        self.nodes, self.faces, self.cells = {}, {}, {}
        self.used = []          # global ids of the 2-D elements that gave faces
        self.kinds = np.array([blk.kind for blk in model.blocks], dtype=object)

    def add_nodes(self, name, ids):
        self.nodes[name] = np.union1d(self.nodes.get(name, np.zeros(0, np.int64)), ids)

    def add_faces(self, name, ftype, faces):
        self.faces.setdefault(name, {}).setdefault(ftype, []).append(faces)

    def add_elements(self, name, elems, defs):
        """An element set: its solids as cells, its 2-D elements as boundary faces; a 2-D
        element off the boundary in a set the deck declares (*ELSET) is an error, one in
        an *ELEMENT's ELSET= only is left out (gmsh gives every surface of its model one)."""
        m = self.model
        kind = self.kinds[m.block_of[elems]]
        for b in np.unique(m.block_of[elems[kind == SOLID]]):
            rows = m.row_of[elems[m.block_of[elems] == b]]
            ctype = m.blocks[b].ctype
            self.cells.setdefault(name, {}).setdefault(ctype, []).append(self.cell_of[b] + rows)
        faces_of = elems[kind == FACE]
        for ftype, (ids, idx) in self.two_d.items():
            mask = np.isin(ids, faces_of)
            found = idx[mask]
            explicit = [d for _, d in defs if d.explicit]
            if (found < 0).any() and explicit:
                g = int(ids[mask][found < 0][0])
                blk = m.blocks[m.block_of[g]]
                raise explicit[0].keyword.error(
                    f"element set '{name}': {blk.abaqus_type} element "
                    f"{blk.labels[m.row_of[g]]} is not on the boundary of the solid "
                    "elements: expected the faces of a surface")
            if (found >= 0).any():
                self.add_faces(name, ftype, self.boundary.faces[ftype][found[found >= 0]])
                self.used.append(ids[mask][found >= 0])

    def add_surface(self, name, surface, keyword):
        """A surface's faces (and a TYPE=NODE surface's nodes) under its name."""
        for ftype, faces in surface.faces.items():
            for f in faces:
                self.add_faces(name, ftype, f)
        m = self.model
        for elems in surface.free:
            for b in np.unique(m.block_of[elems]):
                el = ELEMENTS[m.blocks[b].ctype]
                conn = m.conn[b][m.row_of[elems[m.block_of[elems] == b]]]
                for ftype, local in el.face_groups.items():
                    faces = conn[:, local].reshape(-1, local.shape[1])
                    hit = self.boundary.match(faces, ftype)
                    self.add_faces(name, ftype, faces[hit >= 0])
        for elems in surface.two_d:
            for ftype, (ids, idx) in self.two_d.items():
                mask = np.isin(ids, elems)
                if (idx[mask] < 0).any():
                    raise keyword.error(f"surface '{name}': a 2-D element of it is not on the "
                                        "boundary of the solid elements")
                self.add_faces(name, ftype, self.boundary.faces[ftype][idx[mask]])
                self.used.append(ids[mask])
        for ids in surface.nodes:
            self.add_nodes(name, ids)

    def add_instance(self, name, body):
        """The cell set of all the solids of an instance."""
        m = self.model
        for b in np.flatnonzero((m.body_of == body) & (self.cell_of >= 0)):
            rows = np.arange(len(m.blocks[b].labels))
            self.cells.setdefault(name, {}).setdefault(m.blocks[b].ctype, []).append(
                self.cell_of[b] + rows)

    def mesh(self, points, cells):
        """The Mesh: nodes used by no solid dropped, faces made unique, empty sets dropped."""
        used = np.unique(np.concatenate([c.ravel() for c in cells.values()]))
        new = np.full(len(points), -1, dtype=np.int64)
        new[used] = np.arange(len(used))
        face_sets = {}
        for name, by_type in self.faces.items():
            kept = {}
            for ftype, parts in by_type.items():
                faces = np.vstack(parts)
                _, first = np.unique(face_key(faces, ELEMENTS[ftype].n_corners), axis=0,
                                     return_index=True)
                if len(first):
                    kept[ftype] = new[faces[np.sort(first)]]
            if kept:
                face_sets[name] = kept
        node_sets = {}
        for name, ids in self.nodes.items():
            kept = np.unique(new[ids])
            if len(kept[kept >= 0]):
                node_sets[name] = kept[kept >= 0]
        for name, faces in face_sets.items():
            node_sets.setdefault(name, face_nodes(faces))
        cell_sets = {name: {t: np.unique(np.concatenate(v)) for t, v in by_type.items()}
                     for name, by_type in self.cells.items()}
        return Mesh(points[used], {t: new[c] for t, c in cells.items()}, node_sets,
                    face_sets, cell_sets)
