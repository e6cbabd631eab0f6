"""The nodes and elements of a deck in one numbering: each instance's copy of its part placed
by its translation and rotation, then the assembly's own (all of a deck without parts).

Labels are local to a body (Abaqus numbers the nodes and elements of each part on their own),
so each body keeps its labels sorted with their global ids; its sets and surfaces are kept by
name in upper case (Abaqus compares names so), with the spelling of their first definition.
"""
from dataclasses import dataclass, field

import numpy as np

from ..placement import rotation_matrix
from .parse import labels_set, parse_elements, parse_nodes, parse_set, set_name


@dataclass(eq=False)
class Body:
    """One instance of a part (name as written) or the assembly (name '')."""
    name: str
    node_labels: np.ndarray          # sorted
    node_ids: np.ndarray             # global node id of each of node_labels
    elem_labels: np.ndarray          # sorted
    elem_ids: np.ndarray             # global element id of each of elem_labels
    nsets: dict = field(default_factory=dict)      # KEY -> [(name as written, SetDef)]
    elsets: dict = field(default_factory=dict)
    surfaces: dict = field(default_factory=dict)   # KEY -> [(name as written, Keyword)]
    sections: list = field(default_factory=list)   # (element set name, Keyword) of each

    @property
    def prefix(self):
        """What the names of its sets start with in the mesh: 'INSTANCE.' ('' for the
        assembly), as the assembly refers to them."""
        return f"{self.name}." if self.name else ""


@dataclass(frozen=True)
class Model:
    """Every body's nodes and elements in global numbering.

    points : (n, 3) coordinates, each instance's placed.
    blocks : the parse.Block of every *ELEMENT keyword, in global element order.
    conn : per block, its node labels as global node ids.
    first : per block, the global id of its first element.
    block_of, row_of : per global element, its block and its row in it.
    body_of : per block, the index of its body.
    """
    bodies: list
    points: np.ndarray
    blocks: list
    conn: list
    first: np.ndarray
    block_of: np.ndarray
    row_of: np.ndarray
    body_of: np.ndarray


def build_model(deck):
    """The Model of a Deck (scopes.read_deck_structure)."""
    parsed = {key: _parse(scope) for key, scope in deck.parts.items()}
    sources = [(i.name, (parsed[i.part], _parse(i.own)), i) for i in deck.instances]
    sources.append(("", (_parse(deck.assembly),), None))
    bodies, points, blocks, conn, body_of = [], [], [], [], []
    n_nodes = n_elems = 0
    for b, (name, parts, instance) in enumerate(sources):
        nodes = [p[0] for p in parts]
        labels = np.concatenate([n.labels for n in nodes])
        xyz = np.vstack([n.points for n in nodes])
        if instance is not None:
            xyz = _placed(xyz, instance)
        node_labels, node_ids = _numbered(labels, n_nodes, nodes, "node")
        own = [blk for p in parts for blk in p[1]]
        elem_labels = np.concatenate([blk.labels for blk in own]) if own else np.zeros(0, int)
        sorted_elems, elem_ids = _numbered(elem_labels, n_elems, own, "element")
        body = Body(name, node_labels, node_ids, sorted_elems, elem_ids)
        for p in parts:
            _add_sets(body, p[2])
        for blk in own:
            conn.append(_node_ids(body, blk))
            blocks.append(blk)
            body_of.append(b)
        bodies.append(body)
        points.append(xyz)
        n_nodes += len(labels)
        n_elems += len(elem_labels)
    sizes = np.array([len(blk.labels) for blk in blocks], dtype=np.int64)
    first = np.cumsum(sizes) - sizes
    block_of = np.repeat(np.arange(len(blocks)), sizes)
    row_of = np.arange(n_elems) - np.repeat(first, sizes)
    return Model(bodies, np.vstack(points), blocks, conn, first, block_of, row_of,
                 np.array(body_of, dtype=np.int64))


def _parse(scope):
    """(Nodes, element Blocks, set and surface definitions) of a scope's keywords."""
    kw = scope.keywords
    nodes = parse_nodes(kw["NODE"])
    blocks = [parse_elements(k) for k in kw["ELEMENT"]]
    defs = []
    for i, k in enumerate(kw["NODE"]):
        if "NSET" in k.params:
            name = set_name(k, "NSET", "node")
            mine = nodes.keyword == i
            defs.append(("N",) + labels_set(k, name, nodes.labels[mine], nodes.row[mine]))
    for blk in blocks:
        if "ELSET" in blk.keyword.params:
            name = set_name(blk.keyword, "ELSET", "cell")
            defs.append(("E",) + labels_set(blk.keyword, name, blk.labels, blk.rows))
    defs += [("N",) + parse_set(k, "NSET", "node") for k in kw["NSET"]]
    defs += [("E",) + parse_set(k, "ELSET", "cell") for k in kw["ELSET"]]
    defs += [("S", set_name(k, "NAME", "surface"), k) for k in kw["SURFACE"]]
    defs += [("X", k.get("ELSET"), k) for k in kw["SECTION"]]
    return nodes, blocks, defs


def _add_sets(body, defs):
    for kind, name, definition in defs:
        if kind == "X":
            body.sections.append((name, definition))
            continue
        table = {"N": body.nsets, "E": body.elsets, "S": body.surfaces}[kind]
        table.setdefault(name.upper(), []).append((name, definition))


def _placed(points, instance):
    """An instance's coordinates: translated, then turned about the axis from a to b."""
    points = points + instance.translate
    if instance.rotate is not None:
        a, b, angle = instance.rotate
        points = (points - a) @ rotation_matrix(b - a, angle).T + a
    return points


def _numbered(labels, offset, sources, what):
    """Labels sorted, with the global ids (offset + position in `labels`) in that order;
    a label defined twice is an error naming its second definition."""
    order = np.argsort(labels, kind="stable")
    ordered = labels[order]
    twice = np.flatnonzero(ordered[1:] == ordered[:-1])
    if len(twice):
        keyword, row = _where(sources, int(order[twice[0] + 1]), what)
        raise keyword.error(f"{what} {ordered[twice[0]]} is defined twice", row)
    return ordered, offset + order


def _where(sources, index, what):
    """(keyword, data row) that define the index-th node (sources: Nodes) or element
    (sources: Blocks)."""
    for source in sources:
        if index < len(source.labels):
            if what == "node":
                return source.keywords[source.keyword[index]], int(source.row[index])
            return source.keyword, int(source.rows[index])
        index -= len(source.labels)
    raise IndexError(index)


def _node_ids(body, blk):
    """A block's node labels as global node ids; a label the body does not define is an
    error naming the element."""
    ids, found = lookup(body.node_labels, body.node_ids, blk.conn.ravel())
    if not found.all():
        k = int(np.flatnonzero(~found)[0])
        e = k // blk.conn.shape[1]
        raise blk.keyword.error(f"element {blk.labels[e]}: node {blk.conn.ravel()[k]} is not "
                                "defined" + (f" in instance '{body.name}'" if body.name else ""),
                                int(blk.rows[e]))
    return ids.reshape(blk.conn.shape)


def lookup(sorted_labels, ids, labels):
    """(ids of labels, mask of the labels found) in a body's sorted labels."""
    labels = np.asarray(labels, dtype=np.int64)
    if len(sorted_labels) == 0:
        return np.zeros(len(labels), dtype=np.int64), np.zeros(len(labels), bool)
    pos = np.minimum(np.searchsorted(sorted_labels, labels), len(sorted_labels) - 1)
    found = sorted_labels[pos] == labels
    return ids[pos], found
