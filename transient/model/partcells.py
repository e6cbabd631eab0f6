"""A part's cells, as the process that reduces the part assembles its K and M from them.

On the components path each part (or each piece of a part) is reduced where a worker has
room for it; shipping it the part's cells and assembling there keeps the part's matrices off
the process that orchestrates the reduction (a part's K and M are two copies of its
element-matrix entries, the cells a fraction of one). A part's cells are its own: the parts
share no node, so its K and M assembled alone are the whole model's diagonal block, entry for
entry, and a piece's cells give the rows of the piece's interior exactly.
"""
import hashlib
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from .assembly import assemble
from .dofs import restricted


@dataclass(frozen=True)
class PartCells:
    """A part's cells and what its K and M on its free dofs are assembled with."""
    points: np.ndarray     # (nodes, 3) the part's nodes [m]
    blocks: tuple          # its model.assembly.CellBlocks, in the part's own node ids
    free: np.ndarray       # (n,) its free dofs in its own numbering (3 node + component), sorted
    degrees: tuple         # (stiffness, mass) quadrature degrees (None: each element's own)
    lumped: bool           # the reduction's mass is the HRZ-lumped diagonal, not consistent M

    @classmethod
    def of(cls, model, name, free, degrees, lumped):
        """The part name's cells in the model (model.cells), free (n,) its free dofs as global
        dof ids."""
        part = model.parts[name]
        offset = part.offset
        blocks = tuple(replace(b, conn=b.conn - offset) for n, b in model.cells if n == name)
        return cls(np.asarray(part.mesh.points, dtype=float), blocks,
                   np.asarray(free) - 3 * offset, tuple(degrees), bool(lumped))

    @property
    def n_cells(self):
        return sum(len(b.conn) for b in self.blocks)

    def matrices(self):
        """(K, M) of these cells on the free dofs."""
        return self.on([(None, None)])[0]

    def on(self, blocks):
        """[(K, M) of these cells on rows x cols for (rows, cols) in blocks]: positions among
        the free dofs, sorted (None: all), from one assembly."""
        ops = assemble(self.points, self.blocks, *self.degrees)
        M = sp.diags(ops.lumped_mass).tocsr() if self.lumped else ops.M
        return [tuple(restricted((ops.K, M), *[self.free if i is None else self.free[i]
                                               for i in (rows, cols)]))
                for rows, cols in blocks]

    def subset(self, keep):
        """The cells where keep (n_cells,) bool, in their order, on the same nodes and dofs."""
        blocks, at = [], 0
        for b in self.blocks:
            k = np.asarray(keep[at:at + len(b.conn)])
            at += len(b.conn)
            if k.any():
                blocks.append(_cells(b, k))
        return replace(self, blocks=tuple(blocks))

    def digest(self, h=None):
        """h (a hashlib object, new if None) updated with everything K and M depend on."""
        h = h or hashlib.sha256()
        h.update(repr((self.degrees, self.lumped)).encode())
        arrays = [self.points, self.free]
        for b in self.blocks:
            h.update(b.cell_type.encode())
            arrays += [b.conn, b.young, b.poisson, b.density,
                       np.zeros(0) if b.loss is None else b.loss]
            if b.anisotropy is not None:
                a = b.anisotropy
                h.update(repr((a.orientations, a.names)).encode())
                arrays += [a.material, a.D]
        for a in arrays:
            a = np.ascontiguousarray(a)
            h.update(repr((a.dtype.str, a.shape)).encode())
            h.update(a.data)
        return h


def _cells(block, keep):
    """The CellBlock of block's cells where keep, each cell's constants with it."""
    def each(a):
        return a if a is None or np.ndim(a) == 0 else np.asarray(a)[keep]
    anisotropy = block.anisotropy
    if anisotropy is not None:
        anisotropy = replace(anisotropy, material=anisotropy.material[keep])
    return replace(block, conn=block.conn[keep], young=each(block.young),
                   poisson=each(block.poisson), density=each(block.density),
                   loss=each(block.loss), anisotropy=anisotropy)
