"""Modal analysis against beam theory, rigid modes of a free block, and backends agreeing."""
import numpy as np
import pytest
import scipy.linalg as sla

from transient.model.assembly import CellBlock, assemble
from transient.mesh.generators import box
from transient.solve.linsolve import available
from transient.solve.modes import normal_modes

E, NU, RHO = 2.1e11, 0.3, 7800.0


def timoshenko_cantilever(L, b, h, n_modes, n_el=1000):
    """Bending frequencies [Hz] of a clamped-free Timoshenko beam (rotary inertia and shear).

    An independent 1D oracle: linear elements with one-point shear integration (no locking),
    converged to well below 1e-4 with thousands of elements. Shear coefficient of a rectangle
    (Cowper): 10 (1 + nu) / (12 + 11 nu).
    """
    A, I = b * h, b * h ** 3 / 12
    G = E / (2 * (1 + NU))
    kappa = 10 * (1 + NU) / (12 + 11 * NU)
    le = L / n_el
    n = 2 * (n_el + 1)      # (w, psi) per node
    K = np.zeros((n, n))
    M = np.zeros((n, n))
    kb = E * I / le * np.array([[0, 0, 0, 0], [0, 1, 0, -1], [0, 0, 0, 0], [0, -1, 0, 1.0]])
    # shear strain w' - psi at the element centre
    s = np.array([-1 / le, -0.5, 1 / le, -0.5])
    ks = kappa * G * A * le * np.outer(s, s)
    mw = RHO * A * le / 6 * np.array([[2, 1], [1, 2.0]])
    mp = RHO * I * le / 6 * np.array([[2, 1], [1, 2.0]])
    for e in range(n_el):
        d = np.arange(2 * e, 2 * e + 4)
        K[np.ix_(d, d)] += kb + ks
        M[np.ix_(d[[0, 2]], d[[0, 2]])] += mw
        M[np.ix_(d[[1, 3]], d[[1, 3]])] += mp
    free = np.arange(2, n)
    lam = sla.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True,
                   subset_by_index=[0, n_modes - 1])
    return np.sqrt(lam) / (2 * np.pi)


def block_operators(mesh):
    ne = len(mesh.cells[next(iter(mesh.cells))])
    blocks = [CellBlock(t, c, np.full(len(c), E), np.full(len(c), NU), np.full(len(c), RHO))
              for t, c in mesh.cells.items()]
    assert ne > 0
    return assemble(mesh.points, blocks)


@pytest.mark.parametrize("element, divisions", [("hexahedron20", (20, 2, 2)),
                                                 ("tetra10", (20, 2, 2)),
                                                 ("wedge15", (20, 2, 2))])
@pytest.mark.slow
def test_cantilever_bending_frequencies_match_timoshenko(element, divisions):
    L, h = 1.0, 0.1     # L / h = 10: shear and rotary inertia matter (a few %)
    mesh = box((L, h, h), divisions, element=element)
    ops = block_operators(mesh)
    fixed = np.zeros(ops.K.shape[0], bool)
    root = mesh.node_sets["xmin"]
    for d in range(3):
        fixed[3 * root + d] = True
    modes = normal_modes(ops.K, ops.M, fixed, count=6)
    beam = timoshenko_cantilever(L, h, h, 2)
    euler = np.array([1.875104, 4.694091]) ** 2 / (2 * np.pi) * np.sqrt(E * h ** 2 / 12 / RHO)
    assert np.all(beam < euler)     # the oracle carries the Timoshenko corrections
    # square section: each bending frequency is a pair (bending in y and in z)
    f = modes.frequencies
    np.testing.assert_allclose(f[[0, 1]], beam[0], rtol=0.01)
    np.testing.assert_allclose(f[[2, 3]], beam[1], rtol=0.01)


@pytest.mark.parametrize("element", ["hexahedron", "hexahedron20", "tetra", "tetra10", "wedge",
                                     "wedge15"])
def test_free_block_has_exactly_six_rigid_modes(element):
    mesh = box((0.3, 0.2, 0.1), (3, 2, 2), element=element)
    ops = block_operators(mesh)
    modes = normal_modes(ops.K, ops.M, None, count=8, shift=-1.0)
    f = np.abs(modes.frequencies)
    assert np.all(f[:6] < 1e-3 * f[6])
    assert f[6] > 1000.0


@pytest.mark.parametrize("backend", available())
def test_backends_agree_with_dense(backend):
    mesh = box((0.4, 0.1, 0.1), (16, 3, 3), element="hexahedron")
    ops = block_operators(mesh)
    fixed = np.zeros(ops.K.shape[0], bool)
    fixed[3 * mesh.node_sets["xmin"][:, None] + np.arange(3)] = True
    assert (~fixed).sum() > 600        # large enough to take the sparse path
    modes = normal_modes(ops.K, ops.M, fixed, count=8, backend=backend)
    assert modes.backend == backend
    free = np.flatnonzero(~fixed)
    lam = sla.eigh(ops.K[free][:, free].toarray(), ops.M[free][:, free].toarray(),
                   eigvals_only=True, subset_by_index=[0, 7])
    np.testing.assert_allclose(modes.frequencies, np.sqrt(lam) / (2 * np.pi), rtol=1e-9)
    # mass-normalized shapes
    phi = modes.shapes
    np.testing.assert_allclose(phi.T @ (ops.M @ phi), np.eye(8), atol=1e-9)


@pytest.mark.slow
def test_fmax_returns_every_mode_below_it():
    mesh = box((0.4, 0.1, 0.1), (12, 3, 3), element="hexahedron")
    ops = block_operators(mesh)
    fixed = np.zeros(ops.K.shape[0], bool)
    fixed[3 * mesh.node_sets["xmin"][:, None] + np.arange(3)] = True
    all_modes = normal_modes(ops.K, ops.M, fixed, count=60)
    fmax = 0.5 * (all_modes.frequencies[40] + all_modes.frequencies[41])
    some = normal_modes(ops.K, ops.M, fixed, count=5, fmax=fmax)
    assert len(some.frequencies) == 41
    np.testing.assert_allclose(some.frequencies, all_modes.frequencies[:41], rtol=1e-9)


@pytest.mark.slow
def test_pardiso_is_found_without_importing_pypardiso():
    """The MKL runtime is loaded from where the wheel puts it: importing pypardiso builds a
    solver that globs the environment's lib tree (0.6 s a process), so it is not imported
    when the runtime is there."""
    import subprocess
    import sys
    code = ("import sys; from transient.solve.linsolve import available; "
            "print('pardiso' in available(), 'pypardiso' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    if out[0] != "True":
        pytest.skip("PARDISO is not installed")
    assert out[1] == "False"


def test_the_arpack_fallback_runs_without_the_stalled_lanczos_basis(monkeypatch):
    """When the block Lanczos stalls, ARPACK finds the same modes, and runs after the
    exception is gone: its traceback held the Lanczos' frame and basis (4 GB at 1M dofs, held
    beside the factors through ARPACK's solves). Checked with a weak reference."""
    import weakref

    import scipy.sparse as sp

    from transient.solve import modes as modes_module
    from transient.solve.lanczos import NotConverged

    class Basis:
        pass
    refs, seen = [], []

    def stalled(*args, **kwargs):
        basis = Basis()
        refs.append(weakref.ref(basis))
        raise NotConverged("stalled")

    arpack = modes_module._arpack

    def checked(*args):
        seen.append(refs[0]() is None)
        return arpack(*args)
    monkeypatch.setattr(modes_module, "block_lanczos", stalled)
    monkeypatch.setattr(modes_module, "_arpack", checked)
    n = 800
    K = sp.diags([-np.ones(n - 1), 2.0 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1]).tocsr()
    M = sp.identity(n, format="csr")
    out = normal_modes(K * 1e6, M, count=6)
    assert seen == [True] and "ARPACK" in out.backend and "stalled" in out.backend
    lam = sla.eigh(K.toarray() * 1e6, eigvals_only=True)[:6]
    assert np.allclose((2 * np.pi * out.frequencies) ** 2, lam, rtol=1e-8)
