"""`transient run`: the stages of a transient, then the time integration streamed to HDF5.

Stages (each runs only if the scene needs it, and is timed): model, contact, preload,
linearization, reduction, time step, integration. The kernels integrate chunks of steps; between
chunks Python appends the outputs to the history, writes a checkpoint, checks the energy balance
and the critical step, and moves the progress bar.
"""
import copy
import sys
import time
from pathlib import Path
from dataclasses import dataclass, field, replace

import h5py
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from . import __version__
from .coarse import subset_rule
from .contact import build_contact, contact_stiffness
from .contactset import stack
from .errors import CaseError, RunAborted
from .linsolve import FactorizationError, factorize, triangular_factors
from .history import CASE_TEXT, History, load_checkpoint
from .lowrank import ContactSolver
from .kernels import newmark, stepping
from .kernels.laws import EXPONENTIAL
from .model import build_model
from .preload import Preload, PreloadError, solve_preload
from .reduction import exponential_coefficients, reduced_basis
from .sampling import ReducedPreloadError, sample_contact
from .signals import compile_signals

ENERGY_TERMS = ("kinetic", "strain", "contact", "external_work", "dissipated")
MAX_WOODBURY_BYTES = 2e9   # implicit full model: S^-1 C^T is kept dense
SHIFT_HZ = 1.0     # -(2 pi SHIFT_HZ)^2 shifts K so that floating parts stay solvable


@dataclass
class Problem:
    """What the kernels integrate, in reduced coordinates or on the free dofs."""
    reduced: bool
    state: np.ndarray        # (5, n): q, v, a, [3, 0] the time, forces of the previous step
    acc: np.ndarray          # (2,) external work and dissipated energy
    dt: float
    dt_critical: float       # explicit stability limit at the preload (inf when not explicit)
    args: tuple              # the kernel's system arguments
    n_points: int
    sensor_names: tuple
    contact_slices: dict
    store_contact: bool
    contacts: object         # the ContactSet: weights and laws of the points
    sensors: object          # (n_sensors, n) observation of the state q (dense or CSR)
    stages: dict = field(default_factory=dict)
    meta: dict = field(default_factory=dict)
    initial_energy: np.ndarray = None
    initial_row: tuple = None         # the outputs at the initial state (the history's row 0)
    gmin: np.ndarray = None           # (m,) smallest gap of each point so far
    kt_checked: np.ndarray = None     # (m,) contact tangents the critical step accounts for
    crit_rows: np.ndarray = None      # (m,) |C_i M^-1/2|^2 of each contact row
    crit_omega2: float = 0.0          # omega_max^2 at the preload, contact included
    mass: object = None               # full model, implicit: the mass matrix on the free dofs
    n_field: int = 0                  # observed rows after the sensors: the state q itself
    store_energy: bool = True
    geometry: dict = field(default_factory=dict)   # fixed arrays of the history (/geometry)
    T: np.ndarray = None              # reduced model: u = T q (ndof, n)
    free: np.ndarray = None           # full model: the free dofs q lives on


def _timed(stages, name, fn, *args, **kwargs):
    t0 = time.perf_counter()
    out = fn(*args, **kwargs)
    stages[name] = time.perf_counter() - t0
    return out


def _signals(case):
    specs = [case["loads"][name]["signal"] for name in case["loads"]]
    return compile_signals(specs)


def _initial_velocity(case, model):
    v = np.zeros(model.ndof)
    for name, spec in case["initial"].items():
        if spec["part"] not in model.parts:
            raise CaseError(case.path, f"initial.{name}.part", f"unknown part '{spec['part']}' "
                            f"(parts: {', '.join(model.parts)})")
        dofs = model.part_dofs(spec["part"]).reshape(-1, 3)
        v[dofs] = spec["velocity"]
    v[model.fixed] = 0.0
    return v


def _critical_kt(contacts, preload):
    """Contact tangent for the critical step: the preload's, and k for penalty laws (they may
    close during the run)."""
    kt = preload.tangent.copy()
    penalty = contacts.code != EXPONENTIAL
    kt[penalty] = np.maximum(kt[penalty], contacts.params[penalty, 0])
    return kt


def _blocks(m):
    """Row blocks of the contact pass, one per Numba thread."""
    import numba
    nb = max(1, min(numba.get_num_threads(), m // 64 or 1))
    return np.linspace(0, m, nb + 1).astype(np.int64)


def prepare(case, quiet=True):
    """Model, contact, preload, linearization and (optionally) reduction of a case."""
    solver = case["solver"]
    stages = {}
    model = _timed(stages, "model", build_model, case)
    pairs = _timed(stages, "contact", build_contact, case, model) if case["contact"] else []
    contacts = stack(pairs, model.ndof)
    patterns = [model.load_patterns[name] for name in case["loads"]]
    constant = sum((p for p, name in zip(patterns, case["loads"])
                    if case["loads"][name]["signal"]["kind"] == "constant"),
                   np.zeros(model.ndof))
    free = np.flatnonzero(~model.fixed)
    # without constant loads there is no preload: the run starts from the undeformed state
    # (with initial velocities), in equilibrium or not
    needs_preload = bool(np.any(constant))
    cs = None
    if needs_preload or solver["reduction"]["enabled"]:
        cs = _timed(stages, "factorization", ContactSolver, model.K[free][:, free],
                    model.M[free][:, free], contacts.C[:, free], -(2 * np.pi * SHIFT_HZ) ** 2,
                    solver["linear_solver"])
    try:
        preload = _timed(stages, "preload", solve_preload, model.K, model.fixed,
                         constant if needs_preload else np.zeros(model.ndof), contacts, cs,
                         solver["newton"]["tolerance"], solver["newton"]["max_iter"])
    except PreloadError as exc:
        raise CaseError(case.path, "loads", str(exc)) from None
    if preload.iterations == 0:
        del stages["preload"]
    t0 = time.perf_counter()
    kw = [contacts.weights[s] * preload.tangent[s] for s in contacts.slices.values()]
    K_lin = (model.K + contact_stiffness(pairs, model.ndof, kw=kw)).tocsr() if pairs else model.K
    if pairs:
        stages["linearization"] = time.perf_counter() - t0
    v0 = _initial_velocity(case, model)
    sig = _signals(case)
    damping = solver["damping"]
    reduction = solver["reduction"]
    if solver["scheme"] == "exponential" and not reduction["enabled"]:
        raise CaseError(case.path, "solver.scheme", "the exponential scheme propagates the modes "
                        "of a reduced model: set solver.reduction.enabled = true")
    candidate = _candidates(case, pairs, contacts)
    if reduction["enabled"]:
        M = sp.diags(model.lumped_mass).tocsr() if solver["mass"] == "lumped" else model.M
        problem, sampled, held = _reduced(case, model, M, contacts, preload, K_lin, patterns,
                                          v0, sig, stages,
                                          cs.solver(contacts.weights * preload.tangent),
                                          candidate)
        if sampled is not None:
            # from here on the points kept, and the preload they hold
            pairs = _sampled_pairs(pairs, contacts, sampled.keep, sampled.contacts)
            contacts, preload = sampled.contacts, held
            problem.meta["sampling"] = {"candidates": int(candidate.sum()),
                                        "points": int(len(sampled.sample.chosen)),
                                        "residual": sampled.sample.residual,
                                        "band_modes": sampled.sample.band,
                                        "preload_iterations": sampled.iterations}
    else:
        if damping["modal"] > 0:
            raise CaseError(case.path, "solver.damping.modal", "modal damping needs the reduced "
                            "model (solver.reduction.enabled = true); use alpha and beta")
        if solver["mass"] == "consistent" and solver["scheme"] == "explicit":
            raise CaseError(case.path, "solver.mass", "central differences on the full model "
                            "need the lumped mass: use lumped (or auto), or a reduced model")
        problem = _full(case, model, contacts, preload, K_lin, patterns, v0, sig, stages)
    problem.meta.update({
        "preload_iterations": preload.iterations, "preload_residual": preload.residual,
        "preload_contact_force": {name: float((contacts.weights * preload.pressure)[s].sum())
                                  for name, s in contacts.slices.items()},
        "n_points": contacts.n_points,
        "pairs": {p.name: {"rule": p.spec["rule"], "points": p.rule.n_points,
                           "regularized": p.spec["regularized"], "eps": p.eps,
                           "kept": p.compat.kept(p.eps) if p.compat else None,
                           "candidates": p.candidates or None,
                           "law": p.spec["law"]["kind"]} for p in pairs}})
    output = case["output"]
    problem.n_field = problem.state.shape[1] if output["field"] else 0
    problem.store_energy = output["energy"]
    if output["field"] and problem.reduced:
        # u = T q: kept so that an export needs no rebuild of the basis (a rebuild repeats
        # the setup, and its rank decisions may differ with the BLAS threads)
        problem.geometry["field/basis"] = problem.T
    if output["contact"]:
        for p in pairs:
            problem.geometry.update({f"contact/{p.name}/points": p.rule.points,
                                     f"contact/{p.name}/normals": p.rule.normals,
                                     f"contact/{p.name}/weights": p.rule.weights})
    return problem


def _candidates(case, pairs, contacts):
    """Mask of the points a sampled rule picks from (None when no pair is sampled)."""
    sampled = [p for p in pairs if p.spec["rule"] == "sampled"]
    if not sampled:
        return None
    if not case["solver"]["reduction"]["enabled"]:
        raise CaseError(case.path, f"contact.{sampled[0].name}.rule", "the sampled rule picks "
                        "its points on the reduced model: set solver.reduction.enabled = true")
    mask = np.zeros(contacts.n_points, bool)
    for p in sampled:
        mask[contacts.slices[p.name]] = True
    return mask


def _sampled_pairs(pairs, rich, keep, contacts):
    """The pairs with the rules of the points kept (sampled pairs: chosen points and weights)."""
    out = []
    for p in pairs:
        s, new = rich.slices[p.name], contacts.slices[p.name]
        local = keep[new] - s.start
        if len(local) == s.stop - s.start:
            out.append(p)
            continue
        out.append(replace(p, rule=subset_rule(p.rule, local, contacts.weights[new]),
                           candidates=s.stop - s.start))
    return out


def _sample(case, contacts, candidate, omega2, Cr, q0, preload):
    """The sampled rule's points (sampling.py), with the reduced preload they hold. The points
    of every sampled pair are chosen together, to the first one's tolerance and cap."""
    solver = case["solver"]
    name = next(n for n, s in contacts.slices.items() if candidate[s].any())
    spec = case["contact"][name]
    band = int(np.sum(omega2 <= (2 * np.pi * solver["reduction"]["fmax"]) ** 2))
    try:
        return sample_contact(contacts, candidate, omega2, Cr, q0, preload.gap,
                              preload.pressure, preload.tangent, band,
                              spec["sampling_tolerance"], spec["points"],
                              solver["newton"]["tolerance"], solver["newton"]["max_iter"])
    except ReducedPreloadError as exc:
        raise CaseError(case.path, f"contact.{name}.sampling_tolerance", str(exc)) from None


def _reduced(case, model, M, contacts, preload, K_lin, patterns, v0, sig, stages, solve,
             candidate=None):
    solver = case["solver"]
    reduction = solver["reduction"]
    free = np.flatnonzero(~model.fixed)
    loads = [np.stack(patterns, axis=1)] if patterns and reduction["statics"] else []
    loads.append(K_lin @ preload.u[:, None])          # its response is the preload itself
    statics = np.hstack(loads)
    kt_crit = _critical_kt(contacts, preload)
    contact = ((contacts.C, contacts.weights * kt_crit)
               if reduction["statics"] and contacts.n_points else None)
    basis = _timed(stages, "reduction", reduced_basis, K_lin, M, model.fixed,
                   reduction["fmax"], statics, solve, SHIFT_HZ, contact,
                   reduction["statics_tolerance"])
    T = basis.T
    MT = M @ T
    q0 = MT.T @ preload.u
    v = MT.T @ v0
    omega2 = basis.omega2
    projection = float(np.linalg.norm(T @ q0 - preload.u)
                       / max(np.linalg.norm(preload.u), 1e-300))
    sampled = None
    if candidate is not None:
        sampled = _timed(stages, "sampling", _sample, case, contacts, candidate, omega2,
                         np.asarray(contacts.C @ T), q0, preload)
        T = T @ sampled.W
        omega2, q0, v = sampled.omega2, sampled.q, sampled.W.T @ v
        contacts = sampled.contacts
        preload = Preload(T @ q0, sampled.gap, sampled.pressure, sampled.tangent,
                          preload.iterations + sampled.iterations, sampled.residual,
                          preload.seconds)
        kt_crit = _critical_kt(contacts, preload)
    damping = solver["damping"]
    omega = np.sqrt(omega2)
    above = omega > 2 * np.pi * reduction["fmax"]
    ratio = damping["modal"] + damping["residual"] * above
    damp = 2 * ratio * omega + damping["alpha"] + damping["beta"] * omega2
    Cr = np.ascontiguousarray(contacts.C @ T)
    kt0 = preload.tangent
    P = _patterns([T.T @ p for p in patterns], T.shape[1])
    S = np.ascontiguousarray(_observed(case, model.sensors) @ T)
    if case["output"]["field"]:
        S = np.vstack([S, np.eye(T.shape[1])])
    state = np.zeros((5, len(omega2)))
    state[0], state[1] = q0, v
    dt_crit = _reduced_critical_step(omega2, Cr, contacts.weights * (kt_crit - kt0))
    blocks = _blocks(contacts.n_points)
    args = (omega2, damp, Cr, contacts.gap0, contacts.weights, kt0, contacts.code,
            contacts.params, P, sig, S, blocks)
    problem = Problem(True, state, np.zeros(2), 0.0, dt_crit, args, contacts.n_points,
                      _sensor_names(case, model), contacts.slices, case["output"]["contact"],
                      contacts, S, stages)
    _critical_data(problem, preload, kt_crit, np.einsum("ij,ij->i", Cr, Cr))
    problem.T = T
    problem.meta.update({"reduced_dofs": len(omega2), "normal_modes": basis.n_modes,
                         "contact_shapes": basis.n_contact_shapes,
                         "basis_timings": basis.timings,
                         "basis_projection_error": projection, "free_dofs": len(free)})
    _initial_acceleration(problem)
    return problem, sampled, preload


def _reduced_critical_step(omega2, Cr, dkw):
    """2 / omega_max of diag(omega^2) + Cr^T diag(dkw) Cr (Lanczos on the small dense matrix)."""
    A = np.diag(omega2) + (Cr.T * dkw) @ Cr if len(dkw) else np.diag(omega2)
    lam = np.linalg.eigvalsh(0.5 * (A + A.T))[-1]
    return 2.0 / np.sqrt(lam) if lam > 0 else np.inf


def _full(case, model, contacts, preload, K_lin, patterns, v0, sig, stages):
    t0 = time.perf_counter()
    free = np.flatnonzero(~model.fixed)
    Kf = K_lin[free][:, free].tocsr()
    mass = model.lumped_mass[free]
    Cf = contacts.C[:, free].tocsr()
    kt0 = preload.tangent
    damping = case["solver"]["damping"]
    kt_crit = _critical_kt(contacts, preload)
    Kc = (Kf + (Cf.T @ sp.diags(contacts.weights * (kt_crit - kt0)) @ Cf)).tocsr()
    dt_crit = _full_critical_step(Kc, mass)
    stages["time_step"] = time.perf_counter() - t0
    P = _patterns([p[free] for p in patterns], len(free))
    S = sp.csr_matrix(_observed(case, model.sensors)[:, free])
    if case["output"]["field"]:
        S = sp.vstack([S, sp.eye(len(free))]).tocsr()
    state = np.zeros((5, len(free)))
    state[0], state[1] = preload.u[free], v0[free]
    args = (_csr(Kf), mass, damping["alpha"], damping["beta"], _csr(Cf), contacts.gap0,
            contacts.weights, kt0, contacts.code, contacts.params, P, sig, _csr(S))
    problem = Problem(False, state, np.zeros(2), 0.0, dt_crit, args, contacts.n_points,
                      _sensor_names(case, model), contacts.slices, case["output"]["contact"],
                      contacts, S, stages)
    _critical_data(problem, preload, kt_crit,
                   np.asarray(Cf.multiply(Cf) @ (1.0 / mass)).ravel())
    problem.meta["free_dofs"] = len(free)
    problem.free = free
    _initial_acceleration(problem)
    if case["solver"]["scheme"] == "implicit":
        consistent = case["solver"]["mass"] != "lumped"
        problem.mass = model.M[free][:, free].tocsr() if consistent else sp.diags(mass).tocsr()
        if consistent:
            # the lumped initial acceleration, redone with the consistent mass
            alpha = damping["alpha"]
            force = mass * (problem.state[2] + alpha * problem.state[1])
            problem.state[2] = factorize(problem.mass)(force) - alpha * problem.state[1]
    return problem


def _observed(case, sensors):
    """The sensor rows observed: none unless the case stores them."""
    return sensors if case["output"]["sensors"] else sensors[:0]


def _sensor_names(case, model):
    return tuple(model.sensor_names) if case["output"]["sensors"] else ()


def _patterns(vectors, n):
    """Load patterns as rows (J, n) for the kernels."""
    return np.ascontiguousarray(np.array(vectors, dtype=float).reshape(len(vectors), n))


def _critical_data(problem, preload, kt_crit, rows):
    """What rechecking the critical step needs: the tangents it accounts for, the rows'
    |C_i M^-1/2|^2, omega_max^2 at the preload, and the smallest gaps so far."""
    problem.gmin = preload.gap.copy()
    problem.kt_checked = kt_crit
    problem.crit_rows = rows
    problem.crit_omega2 = (2.0 / problem.dt_critical) ** 2 if np.isfinite(
        problem.dt_critical) else 0.0


def recheck_critical_step(problem, dt):
    """The largest stable step at the deepest penetration reached (central differences):
    omega_max^2 <= omega_0^2 + sum_i w_i dk_t,i |C_i M^-1/2|^2 (a bound, so on the safe side),
    with dk_t the tangents' growth beyond those the step was chosen for."""
    _, kt, _ = problem.contacts.laws(problem.gmin)
    grow = np.maximum(kt - problem.kt_checked, 0.0)
    if not np.any(grow):
        return problem.dt_critical
    bound = problem.crit_omega2 + np.sum(problem.contacts.weights * grow * problem.crit_rows)
    return 2.0 / np.sqrt(bound)


def _csr(A):
    A = sp.csr_matrix(A)
    return (A.indptr.astype(np.int64), A.indices.astype(np.int64), A.data.astype(np.float64))


def _full_critical_step(K, mass):
    """2 / omega_max for M^-1 K with a diagonal mass (Lanczos on D^-1/2 K D^-1/2)."""
    d = sp.diags(1.0 / np.sqrt(mass))
    A = (d @ K @ d).tocsr()
    v0 = np.ones(A.shape[0])      # a fixed start: the same dt on every run of a case
    lam = spla.eigsh(A, k=1, which="LA", return_eigenvectors=False, tol=1e-6, v0=v0)[0]
    # Lanczos converges from below: a small margin keeps the estimate an upper bound
    return 2.0 / np.sqrt(1.01 * lam)


def simulate(case, problem, dt, n_steps, every=1):
    """Integrate a prepared problem in memory with the case's scheme (no history file, no
    checks between chunks): for tests and benchmarks that compare schemes on one setup.

    Returns (series, status, kernel seconds): series maps "time", "sensors/<name>",
    "energy/<term>" and, if the case stores contact, "contact/gap" and "contact/pressure" (all
    points) to arrays with one row per `every` steps, the initial state first.
    """
    problem = copy.copy(problem)
    problem.state, problem.acc = problem.state.copy(), problem.acc.copy()
    problem.gmin = problem.gmin.copy()
    if problem.reduced:
        problem.args = problem.args[:-1] + (np.array([0, problem.n_points], np.int64),)
    kernel, args = scheme_kernel(case, problem, dt)
    out = _outputs(problem, n_steps // every)
    t0 = time.perf_counter()
    code, done = kernel(problem.state, problem.acc, n_steps, every, dt, *args, *out)
    seconds = time.perf_counter() - t0
    rows = [np.concatenate([first[:1], x[:done // every]])
            for first, x in zip(problem.initial_row, out)]
    series = {"time": rows[0]}
    series.update({f"sensors/{name}": rows[1][:, k]
                   for k, name in enumerate(problem.sensor_names)})
    series.update({f"energy/{term}": rows[4][:, k] for k, term in enumerate(ENERGY_TERMS)})
    if problem.store_contact:
        series["contact/gap"], series["contact/pressure"] = rows[2], rows[3]
    status = {stepping.OK: "complete", stepping.NOT_FINITE: "not finite",
              stepping.NO_CONVERGENCE: "no convergence"}[code]
    return series, status, seconds


def kernel_of(problem):
    return stepping.explicit_reduced if problem.reduced else stepping.explicit_full


def scheme_kernel(case, problem, dt):
    """The kernel of the case's scheme and its system arguments at step dt."""
    solver = case["solver"]
    scheme = solver["scheme"]
    if scheme == "explicit":
        return kernel_of(problem), problem.args + (problem.gmin,)
    newton = solver["newton"]
    if scheme == "implicit" and not problem.reduced:
        return newmark.newmark_full, _newmark_full_args(case, problem, dt) + (
            newton["tolerance"], newton["max_iter"])
    omega2, damp, Cr, g0, w, kt0, code, params, P, sig, S, blocks = problem.args
    if scheme == "implicit":
        # the iteration operator is diagonal: Z = S^-1 C^T row by row
        op = 1.0 + 0.5 * dt * damp + 0.25 * dt * dt * omega2
        Z = np.ascontiguousarray(Cr.T / op[:, None])
        return newmark.newmark_reduced, (
            damp, omega2, Cr, g0, w, kt0, code, params, P, sig, S, blocks, Z, Cr @ Z,
            newton["tolerance"], newton["max_iter"])
    coef = exponential_coefficients(omega2, damp, dt)
    if solver["corrector"] == "implicit":
        # the end state moves by D = diag(G1x) per unit end force: Z = D C^T, G = C Z
        if 8.0 * len(g0) ** 2 > MAX_WOODBURY_BYTES:
            raise CaseError(case.path, "solver.corrector", f"the implicit corrector keeps "
                            f"C D C^T dense: {len(g0)} contact points is "
                            f"{8e-9 * len(g0) ** 2:.1f} GB; sample the points "
                            f"(contact rule \"sampled\") or use corrector \"evaluated\"")
        Z = np.ascontiguousarray(coef[:, 6:7] * Cr.T)
        return stepping.exponential_implicit, (
            coef, damp, omega2, Cr, g0, w, kt0, code, params, P, sig, S, blocks, Z, Cr @ Z,
            newton["max_iter"], problem.state[4])
    return stepping.exponential_reduced, (coef, damp, omega2, Cr, g0, w, kt0, code, params, P,
                                          sig, S, blocks, solver["corrections"],
                                          solver["corrector"] == "propagated", problem.state[4])


def _newmark_full_args(case, problem, dt):
    """Newmark's iteration operator on the full model, factorized for the kernel, with
    Z = S^-1 C^T and G = C Z for the exact contact corrections."""
    t0 = time.perf_counter()
    K, _, alpha, beta, C, g0, w, kt0, code, params, P, sig, S = problem.args
    Kl = sp.csr_matrix((K[2], K[1], K[0]))
    Cl = sp.csr_matrix((C[2], C[1], C[0]), shape=(len(g0), Kl.shape[0]))
    n, m = Kl.shape[0], len(g0)
    if 8.0 * n * m > MAX_WOODBURY_BYTES:
        raise CaseError(case.path, "solver.scheme", f"the implicit scheme on the full model "
                        f"keeps S^-1 C^T dense: {n} dofs x {m} contact points is "
                        f"{8e-9 * n * m:.1f} GB; use a reduced model (solver.reduction)")
    h = 0.5 * dt
    op = ((1.0 + h * alpha) * problem.mass + (h * beta + h * h) * Kl).tocsr()
    try:
        p_in, L, U, p_out, backend = triangular_factors(op, case["solver"]["linear_solver"])
    except FactorizationError as exc:
        raise CaseError(case.path, "solver", f"Newmark's iteration operator: {exc}") from None
    factor = (p_in, L, U, p_out)
    Z = newmark.factor_columns(factor, C, n)
    G = np.ascontiguousarray(Cl @ Z)
    problem.stages["iteration_operator"] = time.perf_counter() - t0
    problem.meta["iteration_operator"] = {"backend": backend, "factor_nonzeros":
                                          int(len(L[2]) + len(U[2]))}
    return (K, _csr(problem.mass), alpha, beta, C, g0, w, kt0, code, params, P, sig, S, factor,
            Z, G)


def _initial_acceleration(problem):
    """a(0) and the initial energies from the forces at the initial state (a step of length 0)."""
    state = problem.state.copy()
    out = _outputs(problem, 1)
    kernel_of(problem)(state, problem.acc.copy(), 1, 1, 0.0, *problem.args,
                       problem.gmin.copy(), *out)
    problem.state[2] = state[2]
    if problem.reduced:
        omega2, damp = problem.args[0], problem.args[1]
        # the forces at t = 0: the first extrapolation then takes them constant
        problem.state[4] = state[2] + omega2 * state[0] + damp * state[1]
    problem.initial_energy = out[-1][0].copy()
    problem.initial_row = out


def _outputs(problem, rows):
    ns = problem.sensors.shape[0]         # the sensors, then the state if stored
    m = problem.n_points if problem.store_contact else 0
    return (np.zeros(rows), np.zeros((rows, ns)), np.zeros((rows, m)), np.zeros((rows, m)),
            np.zeros((rows, 5)))


def _layout(problem):
    layout = {"time": ()}
    layout.update({f"sensors/{name}": () for name in problem.sensor_names})
    if problem.n_field:
        layout["field/q"] = (problem.n_field,)
    if problem.store_contact:
        for name, s in problem.contact_slices.items():
            n = s.stop - s.start
            layout[f"contact/{name}/gap"] = (n,)
            layout[f"contact/{name}/pressure"] = (n,)
    if problem.store_energy:
        layout.update({f"energy/{term}": () for term in ENERGY_TERMS})
    return layout


def _rows(problem, out, n):
    t, s, g, p, e = (x[:n] for x in out)
    rows = {"time": t}
    rows.update({f"sensors/{name}": s[:, k] for k, name in enumerate(problem.sensor_names)})
    if problem.n_field:
        rows["field/q"] = s[:, len(problem.sensor_names):]
    if problem.store_contact:
        for name, sl in problem.contact_slices.items():
            rows[f"contact/{name}/gap"] = g[:, sl]
            rows[f"contact/{name}/pressure"] = p[:, sl]
    if problem.store_energy:
        rows.update({f"energy/{term}": e[:, k] for k, term in enumerate(ENERGY_TERMS)})
    return rows


def _balance(e):
    return e[..., 0] + e[..., 1] + e[..., 2] - e[..., 3] + e[..., 4]


def _mechanical(e):
    """Kinetic + strain + contact energy: the scale of the balance's drift."""
    return np.abs(e[..., 0]) + np.abs(e[..., 1]) + np.abs(e[..., 2])


@dataclass(frozen=True)
class RunResult:
    path: str
    status: str
    steps: int
    t_end: float
    dt: float
    dt_critical: float
    stages: dict
    timings: dict
    energy_drift: float
    meta: dict = None         # what prepare reports: contact points of each pair, reduced dofs


def choose_dt(case, problem, stored=None):
    """The time step: the case's, checked against the critical step, or an automatic one; a
    resumed run keeps the one stored in its history."""
    solver = case["solver"]
    dt = solver["dt"] if stored is None else stored
    if solver["scheme"] in ("exponential", "implicit"):
        # unconditionally stable: the step is set by accuracy, 20 steps per period at fmax
        if dt == 0.0 and not problem.reduced:
            raise CaseError(case.path, "solver.dt", "the implicit scheme on the full model has "
                            "no frequency to resolve: give dt")
        return dt or 1.0 / (20.0 * solver["reduction"]["fmax"])
    if dt == 0.0:
        dt = 0.9 * problem.dt_critical
        if not np.isfinite(dt):
            raise CaseError(case.path, "solver.dt", "no stiffness bounds the step: give dt")
    elif dt > problem.dt_critical and not solver["force_dt"]:
        raise CaseError(case.path, "solver.dt", f"{dt:.3e} s is above the critical step of "
                        f"central differences {problem.dt_critical:.3e} s (set solver.force_dt "
                        "= true to run anyway)")
    return dt


def run(case, path, resume=False, progress=None):
    """Integrate a case to solver.t_end, streaming to the HDF5 file at path.

    Returns a RunResult; a run that stops early (NaN, energy drift, Ctrl-C) keeps every chunk
    in the file, marked `aborted: <reason>`, and its status says so.
    """
    solver, output = case["solver"], case["output"]
    t_start = time.perf_counter()
    problem = prepare(case)
    stored = _stored_dt(path) if resume else None
    dt = choose_dt(case, problem, stored)
    every = output["every"]
    chunk = max(every, solver["chunk"] // every * every)
    n_total = int(round(solver["t_end"] / dt))
    step = 0
    if resume:
        try:
            saved = load_checkpoint(path)
        except (ValueError, KeyError) as exc:
            raise CaseError(path, "", f"--resume: {exc}") from None
    if problem.reduced:
        blocks = saved["blocks"] if resume else _fastest_blocks(case, problem, dt)
        problem.args = problem.args[:-1] + (np.asarray(blocks, np.int64),)
    kernel, args = scheme_kernel(case, problem, dt)
    meta = {CASE_TEXT: case.text, "case_path": str(Path(case.path).resolve()),
            "overrides": list(case.overrides), "version": __version__, "dt": dt,
            "dt_critical": problem.dt_critical, "scheme": solver["scheme"],
            "reduced": problem.reduced, "steps_planned": n_total, "every": every,
            "stages": problem.stages, **problem.meta}
    if resume:
        history = History.open_for_resume(path)
        problem.state[:] = saved["state"]
        problem.acc[:] = saved["acc"]
        problem.gmin[:] = saved["gmin"]
        step = int(saved["step"][0])
    else:
        history = History.create(path, meta, _layout(problem), overwrite=True,
                                 expected_rows=n_total // every + 1, geometry=problem.geometry)
        history.append(_rows(problem, problem.initial_row, 1))
    out = _outputs(problem, chunk // every)
    e0 = _balance(problem.initial_energy)
    peak = max(_mechanical(problem.initial_energy), 1e-300)
    drift = 0.0
    status = "complete"
    t_kernel = 0.0
    bar = _progress_bar(progress, n_total, step)
    with history:
        try:
            while step < n_total:
                n = min(chunk, n_total - step)
                t0 = time.perf_counter()
                code, done = kernel(problem.state, problem.acc, n, every, dt, *args, *out)
                t_kernel += time.perf_counter() - t0
                # a kernel stopping on a non-finite state has not stored that step
                rows = (done - (code == stepping.NOT_FINITE)) // every
                finite = all(np.all(np.isfinite(x[:rows])) for x in out) and \
                    np.all(np.isfinite(problem.state))
                if not finite or code == stepping.NOT_FINITE:
                    # keep only the rows before the first with anything not finite, then stop
                    rows = _finite_rows(out, rows)
                    code = stepping.NOT_FINITE
                if rows:
                    history.append(_rows(problem, out, rows))
                    totals = _balance(out[4][:rows])
                    peak = max(peak, _mechanical(out[4][:rows]).max())
                    drift = max(drift, np.abs(totals - e0).max() / peak)
                if code == stepping.NOT_FINITE:
                    step += rows * every
                    last = out[0][rows - 1] if rows else problem.state[3, 0] - done * dt
                    problem.state[3, 0] = last
                    raise RunAborted(f"state not finite after t = {last:.6g} s (the last "
                                     "finite row kept)")
                step += done
                history.checkpoint({"state": problem.state, "acc": problem.acc,
                                    "step": np.array([step]),
                                    "blocks": problem.args[-1] if problem.reduced
                                    else np.zeros(0), "gmin": problem.gmin})
                bar.update(done)
                if code == stepping.NO_CONVERGENCE:
                    raise RunAborted(f"Newton iterations did not converge in "
                                     f"{solver['newton']['max_iter']} at t = "
                                     f"{problem.state[3, 0]:.6g} s (smaller dt, or a larger "
                                     "solver.newton.max_iter)")
                if solver["scheme"] == "explicit" and not solver["force_dt"]:
                    dt_max = recheck_critical_step(problem, dt)
                    if dt > dt_max:
                        raise RunAborted(f"dt {dt:.3e} s is above the critical step "
                                         f"{dt_max:.3e} s at the deepest penetration reached "
                                         f"({problem.gmin.min():.3e} m) at t = "
                                         f"{problem.state[3, 0]:.6g} s")
                if drift > solver["drift_tolerance"]:
                    raise RunAborted(f"energy balance drifted by {drift:.2e} of the peak "
                                     f"mechanical energy "
                                     f"(tolerance {solver['drift_tolerance']:g}) at "
                                     f"t = {problem.state[3, 0]:.6g} s")
        except RunAborted as exc:
            status = f"aborted: {exc}"
        except KeyboardInterrupt:
            status = "aborted: interrupted"
        finally:
            bar.close()
        history.finish(status, _timings(problem, t_kernel, t_start))
    return RunResult(str(path), status, step, float(problem.state[3, 0]), dt,
                     problem.dt_critical, problem.stages, _timings(problem, t_kernel, t_start),
                     drift, problem.meta)


def _finite_rows(out, rows):
    """How many leading output rows are finite in every output."""
    bad = np.zeros(rows, bool)
    for x in out:
        bad |= ~np.isfinite(x[:rows].reshape(rows, -1)).all(axis=1)
    return int(np.argmax(bad)) if bad.any() else rows


def _fastest_blocks(case, problem, dt, steps=20):
    """Row blocks of the contact pass: one per thread or a single one, whichever runs faster
    here and now (threads stall when the machine's cores are busy). The choice fixes the
    summation order, so a resumed run reuses it."""
    m = problem.n_points
    candidates = [np.array([0, m], np.int64)]
    threaded = _blocks(m)
    if len(threaded) > 2:
        candidates.append(threaded)
    if len(candidates) == 1:
        return candidates[0]
    times = []
    for blocks in candidates:
        problem.args = problem.args[:-1] + (blocks,)
        kernel, args = scheme_kernel(case, problem, dt)
        if kernel is stepping.explicit_reduced:
            args = args[:-1] + (problem.gmin.copy(),)
        best = np.inf
        for _ in range(2):       # the first call may compile
            state, acc = problem.state.copy(), problem.acc.copy()
            out = _outputs(problem, steps)
            if kernel is stepping.exponential_reduced:
                args = args[:-1] + (state[4],)
            t0 = time.perf_counter()
            kernel(state, acc, steps, 1, dt, *args, *out)
            best = min(best, time.perf_counter() - t0)
        times.append(best)
    return candidates[int(np.argmin(times))]


def _stored_dt(path):
    try:
        with h5py.File(path, "r") as f:
            return float(f.attrs["dt"])
    except (OSError, KeyError) as exc:
        raise CaseError(path, "", f"--resume: not a transient history ({exc})") from None


def _timings(problem, t_kernel, t_start):
    setup = sum(problem.stages.values())
    return {"setup": setup, "kernel": t_kernel, "total": time.perf_counter() - t_start}


class _NoBar:
    def update(self, n):
        pass

    def close(self):
        pass


def _progress_bar(progress, total, initial):
    if not progress:
        return _NoBar()
    from tqdm import tqdm
    return tqdm(total=total, initial=initial, unit="step", file=sys.stderr, leave=False,
                smoothing=0.1)
