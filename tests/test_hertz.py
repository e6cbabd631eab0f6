"""Hertz impact: a steel sphere dropped on a rigid wall, meshed with gmsh (tet10, refined at the
pole), against Johnson's closed forms for the contact time and the peak force (Contact
Mechanics, 1985, section 11.4), with the full model and with a reduced one."""
import math

import numpy as np
import pytest

from transient.case.loading import load
from transient.io.stored import open_history
from transient.mesh.meshfile import jacobian_check, read_mesh
from transient.integration import run

gmsh = pytest.importorskip("gmsh")

# A 10 mm radius steel ball at 0.1 m/s. The contact is quasi-static: it lasts 82.8 us, 10.6
# periods of the ball's first elastic mode (128 kHz). The errors grow as it gets less so (the
# same mesh, penalty and steps per t_c; full model): 0.03 m/s (13 periods) t_c -0.3%, F_max
# +1.0%; 0.1 m/s -0.5%, +1.4%; 1 m/s (6.7 periods) -1.0%, +2.3%; 3 m/s (5.4 periods) -1.9%, +3.0%.
R, E, NU, RHO, V = 0.01, 2.1e11, 0.3, 7800.0, 0.1
MASS = 4.0 / 3.0 * math.pi * R ** 3 * RHO


def johnson(young):
    """(delta_max [m], F_max [N], t_c [s]) of the ball on a rigid flat (E* = E / (1 - nu^2)).

    t_c = 2 delta_max / V times the integral of (1 - x^(5/2))^(-1/2) over [0, 1], that is
    2.943 delta_max / V (Johnson's t* = 2.94 delta* / V). The 2.868 often quoted is the
    coefficient of (m^2 / (R E*^2 V))^(1/5), the same time without delta_max: 2.868 delta_max / V
    would be 2.6% short.
    """
    e_star = young / (1.0 - NU ** 2)
    delta = (15.0 * MASS * V ** 2 / (16.0 * e_star * math.sqrt(R))) ** 0.4
    force = 4.0 / 3.0 * e_star * math.sqrt(R) * delta ** 1.5
    integral = 0.4 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)
    return delta, force, 2.0 * integral * delta / V


DELTA, F_MAX, T_C = johnson(E)          # 2.81 um, 145.2 N, 82.8 us
A = math.sqrt(R * DELTA)                # contact radius at the peak: 0.168 mm

# A quarter of the ball (x, y >= 0, symmetry planes x = 0 and y = 0): a quarter of the mass
# and of the force. Elements of A / 3 within R_CAP of the pole, growing as the distance to it
# up to R / 2: 568 tet10, 1181 nodes, 3021 free dofs; the cap has 35 tri6 faces, 105 contact
# points (a degree 2 rule). Elements of A / 2 to A / 6 (2343 to 9342 free dofs) give t_c
# within 0.6% and F_max within 0.2% of these: what is left is the physics (the penalty, the
# dynamics above).
R_CAP = 1.3 * A
H_MIN, H_MAX = A / 3.0, R / 2.0

# Penalty: its own compliance at the peak, p / k = 2 E* / (pi k A), is 1% of the Hertz approach
# (3e16: 3%, and t_c -0.1%, F_max +1.0%; 3e17: 0.3%, and -0.8%, +1.5%). Central differences
# would take 70,000 steps of 1.3 ns, about 40 s on the full model here (the small elements at
# the pole set a critical step of 1.9 ns without the penalty, 1.45 ns with it): implicit
# Newmark takes 103 steps per t_c on both models (half as many: t_c -1.0%, F_max +1.3%).
K_PENALTY = 9e16
GAP = 1e-7                              # the wall 0.1 um below the pole: contact from 1 us
DT = 8e-7
T_END = GAP / V + 1.1 * T_C

CASE = f"""
title = "Hertz impact: a quarter of a steel ball at {V} m/s on a rigid wall"

[materials.steel]
E = {E!r}
nu = {NU!r}
rho = {RHO!r}

[parts.ball]
material = "steel"
[parts.ball.mesh]
kind = "file"
path = "quarter_ball.msh"
[parts.ball.sets.x0]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
[parts.ball.sets.y0]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]

[constraints.x0]
set = "ball.x0"
dofs = ["x"]
[constraints.y0]
set = "ball.y0"
dofs = ["y"]

[initial.drop]
part = "ball"
velocity = [0.0, 0.0, {-V!r}]

[contact.wall]
surface1 = "ball.cap"
wall_point = [0.0, 0.0, {-GAP!r}]
wall_normal = [0.0, 0.0, 1.0]
k = {K_PENALTY!r}
order = 2
[contact.wall.law]
kind = "linear"

[solver]
scheme = "implicit"
dt = {DT!r}
t_end = {T_END!r}

[output]
contact = true
"""

# The reduced model: the 16 normal modes below 300 kHz (the rigid drop and 15 elastic ones)
# and the contact static shapes (85, one per direction the cap's normal dofs span: the
# penalty is so much stiffer than the ball there that all pass the default statics_tolerance),
# 101 dofs. Fewer do as well: fmax = 150 kHz (4 modes, 89 dofs) or statics_tolerance = 0.5
# (79 dofs) are within 0.1% of it. Without the static shapes (reduction.statics = false) the
# modes alone cannot take the contact's local deformation: t_c 76% short, F_max 4 times.
MODELS = {"full": [],
          "reduced": ["solver.reduction.enabled=true", "solver.reduction.fmax=3e5"]}


def quarter_ball(path):
    """The quarter ball in tet10, with the surface around the pole, where the contact is, as a
    physical surface 'cap': a quarter circle of radius R_CAP drawn on the sphere splits its
    face there. (A volume split, by a plane or a small sphere about the pole, leaves
    interfaces inside the ball, a 2 um thin lens of slivers or a curved surface that
    second-order elements of A / 2 follow into inverted cells.)"""
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        occ = gmsh.model.occ
        ball = occ.addSphere(0, 0, R, R, angle1=-math.pi / 2, angle2=math.pi / 2,
                             angle3=math.pi / 2)
        edge = occ.addCircle(0, 0, R - math.sqrt(R * R - R_CAP * R_CAP), R_CAP,
                             angle1=0, angle2=math.pi / 2)
        occ.fragment([(3, ball)], [(1, edge)])
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [v for _, v in gmsh.model.getEntities(3)], name="ball")
        cap = [s for _, s in gmsh.model.getEntities(2) if gmsh.model.getType(2, s) == "Sphere"
               and occ.getCenterOfMass(2, s)[2] < R_CAP]
        gmsh.model.addPhysicalGroup(2, cap, name="cap")
        pole = [p for _, p in gmsh.model.getEntities(0)
                if np.linalg.norm(gmsh.model.getValue(0, p, [])) < 1e-9 * R]
        field = gmsh.model.mesh.field
        distance = field.add("Distance")
        field.setNumbers(distance, "PointsList", pole)
        size = field.add("Threshold")
        field.setNumber(size, "InField", distance)
        field.setNumber(size, "SizeMin", H_MIN)
        field.setNumber(size, "SizeMax", H_MAX)
        field.setNumber(size, "DistMin", R_CAP)
        field.setNumber(size, "DistMax", R_CAP + H_MAX - H_MIN)
        field.setAsBackgroundMesh(size)
        for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints",
                       "MeshSizeFromCurvature"):
            gmsh.option.setNumber(f"Mesh.{option}", 0)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(2)       # midside nodes on the sphere
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


@pytest.fixture(scope="module")
def case_path(tmp_path_factory):
    directory = tmp_path_factory.mktemp("hertz")
    quarter_ball(directory / "quarter_ball.msh")
    mesh = read_mesh(directory / "quarter_ball.msh")
    assert list(mesh.cells) == ["tetra10"] and list(mesh.face_sets["cap"]) == ["triangle6"]
    assert all(det > 0 for _, _, det in jacobian_check(mesh))
    path = directory / "hertz.toml"
    path.write_text(CASE)
    return path


def contact_time(t, force):
    """Time from first touch to separation: F^(2/3) is linear in time where the contact closes
    and opens (F ~ delta^(3/2), delta ~ V t), so each end is extrapolated from the two rows
    inside it, and kept within the step that brackets it."""
    on = np.flatnonzero(force > 0)
    i, j = on[0], on[-1]
    y = force ** (2.0 / 3.0)
    start = t[i] - min(y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i]), t[i] - t[i - 1])
    end = t[j] + min(y[j] * (t[j] - t[j - 1]) / (y[j - 1] - y[j]), t[j + 1] - t[j])
    return end - start


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.slow
def test_hertz_impact_within_5_percent_of_johnson(case_path, model):
    result = run(load(case_path, MODELS[model]), case_path.with_name(f"{model}.h5"))
    assert result.status == "complete"
    history = open_history(result.path)
    t = history.time()
    pressure = history.read("contact/wall/pressure")
    points = history.geometry("contact/wall/points")
    force = 4.0 * (pressure @ history.geometry("contact/wall/weights"))
    on = np.flatnonzero(force > 0)
    # one contact, from after the start to before the end, and the contact area inside the
    # cap: its outer points, past 1.15 A, never touch
    assert 0 < on[0] and on[-1] < len(t) - 1 and np.all(force[on[0]:on[-1] + 1] > 0)
    rim = np.hypot(points[:, 0], points[:, 1]) > 1.15 * A
    assert rim.any() and not pressure[:, rim].any()
    measured = {"t_c": contact_time(t, force), "F_max": force.max()}
    # full: t_c -0.5%, F_max +1.4%; reduced: -0.6%, +1.6%
    assert measured["t_c"] == pytest.approx(T_C, rel=0.05)
    assert measured["F_max"] == pytest.approx(F_MAX, rel=0.05)
    # the check can fail: F_max goes as E*^(2/5) and t_c as E*^(-2/5), so a modulus 25% off
    # moves Johnson's figures by 9-12%; this run is 7-14% from them on each, and the model run
    # with E 25% high is 9% short on t_c and 11% high on F_max
    for wrong in (0.75, 1.25):
        _, force_wrong, time_wrong = johnson(wrong * E)
        assert abs(measured["F_max"] / force_wrong - 1) > 0.05
        assert abs(measured["t_c"] / time_wrong - 1) > 0.05


@pytest.mark.parametrize("corrector, limit", [("propagated", 0.5), ("evaluated", 2.0)])
@pytest.mark.slow
def test_explicit_correctors_of_a_stiff_penalty_are_refused_by_name(case_path, corrector, limit,
                                                                    capsys):
    # the exponential scheme at the implicit runs' step: the penalty, open at the preload, is
    # all remainder, at omega dt = 833 of its own frequency. "propagated" used to report a
    # complete run in which every contact bounced within one step, unseen by the rows
    from transient.cli import main
    sets = MODELS["reduced"] + ['solver.scheme="exponential"', f'solver.corrector="{corrector}"']
    code = main(["run", str(case_path), "-o", str(case_path.with_name("refused.h5")), "--quiet"]
                + [a for s in sets for a in ("--set", s)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert "solver.dt" in err and "contact.wall.k" in err and 'solver.corrector = "implicit"' in err
    assert f"omega dt = 833, above {limit:g}" in err
