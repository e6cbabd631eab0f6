"""Node and element sets of a deck resolved to global ids: labels, GENERATE ranges, sets of
other sets, an assembly's sets of an instance's labels (INSTANCE=) and references across
bodies written 'INSTANCE.NAME' or 'INSTANCE.LABEL', as the assembly level of a deck has them.
"""
import numpy as np

from ..selections import offered
from .bodies import lookup


class _Cycle(Exception):
    """A set that includes itself, through others maybe: args[0] is its name."""


class Resolver:
    """Resolves the sets of a bodies.Model, each once."""

    def __init__(self, model):
        self.model = model
        self.instances = {b.name.upper(): b for b in model.bodies if b.name}
        self.memo = {}

    def nodes(self, body, key):
        """Global node ids of a body's node set (upper-case key)."""
        return self._resolve("node", body, key, ())

    def elements(self, body, key):
        """Global element ids of a body's element set (upper-case key)."""
        return self._resolve("element", body, key, ())

    def reference(self, kind, body, text, keyword, row, stack=()):
        """Global ids of what a data field names: a label, a set name, or either qualified
        by an instance ('Pad-1.12', 'Pad-1.friction') in the assembly."""
        target, rest = self.split(body, text)
        try:
            label = int(rest)
        except ValueError:
            label = None
        if label is not None:
            return self.labels(kind, target, [label], keyword, [row])
        table = target.nsets if kind == "node" else target.elsets
        if rest.upper() not in table:
            what = "node" if kind == "node" else "element"
            known = ", ".join(offered(n for defs in table.values() for n, _ in defs[:1]))
            raise keyword.error(f"{what} set '{rest}' is not defined"
                                + (f" in instance '{target.name}'" if target.name else "")
                                + f" ({what} sets: {known or 'none'})", row)
        return self._resolve(kind, target, rest.upper(), stack)

    def split(self, body, text):
        """(body, name or label) of a field: an assembly's 'INSTANCE.REST' names a field of
        that instance (instance names may hold dots: the longest that fits is taken)."""
        if not body.name and "." in text:
            dots = [i for i, c in enumerate(text) if c == "."]
            for i in reversed(dots):
                inst = self.instances.get(text[:i].upper())
                if inst is not None:
                    return inst, text[i + 1:]
        return body, text

    def instance(self, body, definition):
        """The body whose labels and names a set definition lists (its INSTANCE=)."""
        if definition.instance is None:
            return body
        inst = self.instances.get(definition.instance.upper())
        if inst is None or body.name:
            raise definition.keyword.error(
                f"INSTANCE={definition.instance}: expected an instance of the assembly "
                f"({', '.join(b.name for b in self.instances.values()) or 'none'})")
        return inst

    def labels(self, kind, body, labels, keyword, rows):
        """Global ids of labels of a body; an undefined label is an error."""
        sorted_labels, ids = ((body.node_labels, body.node_ids) if kind == "node"
                              else (body.elem_labels, body.elem_ids))
        found_ids, found = lookup(sorted_labels, ids, labels)
        if not found.all():
            k = int(np.flatnonzero(~found)[0])
            row = None if rows[k] is None else int(rows[k])
            raise keyword.error(f"{kind} {labels[k]} is not defined"
                                + (f" in instance '{body.name}'" if body.name else ""), row)
        return found_ids

    def _resolve(self, kind, body, key, stack):
        memo = (kind, id(body), key)
        if memo in self.memo:
            return self.memo[memo]
        if memo in stack:
            raise _Cycle((body.nsets if kind == "node" else body.elsets)[key][0][0])
        stack = stack + (memo,)
        parts = []
        for name, d in (body.nsets if kind == "node" else body.elsets)[key]:
            target = self.instance(body, d)
            try:
                parts.append(self.labels(kind, target, d.labels, d.keyword, d.rows))
                parts += [self._generated(kind, target, first, last, step)
                          for first, last, step, _ in d.ranges]
                parts += [self.reference(kind, target, text, d.keyword, row, stack)
                          for text, row in d.names]
                if d.elset:
                    elems = self.reference("element", target, d.elset, d.keyword, None)
                    parts.append(self.element_nodes(elems))
            except _Cycle as cycle:
                raise d.keyword.error(f"set '{cycle.args[0]}' includes itself") from None
        ids = np.unique(np.concatenate(parts)) if parts else np.zeros(0, np.int64)
        self.memo[memo] = ids
        return ids

    def _generated(self, kind, body, first, last, step):
        """The labels a body defines among first, first + step, ..., last: the range is
        never listed, so a huge one costs what the body's labels cost."""
        labels, ids = ((body.node_labels, body.node_ids) if kind == "node"
                       else (body.elem_labels, body.elem_ids))
        keep = (labels >= first) & (labels <= last) & ((labels - first) % step == 0)
        return ids[keep]

    def element_nodes(self, elems):
        """Global node ids of the nodes of global elements."""
        m = self.model
        nodes = [m.conn[b][m.row_of[elems[m.block_of[elems] == b]]].ravel()
                 for b in np.unique(m.block_of[elems])]
        return np.unique(np.concatenate(nodes)) if nodes else np.zeros(0, np.int64)

