"""The case file schema: every key, its type, default, unit and meaning.

Tables keyed by name (`[parts.NAME]`) give every value a dotted path. The schema drives
validation (`loading.py`), `--set` overrides, and the key reference in `cases/README.md`
(`python -m transient.case` prints it).
"""
from .geometry import MESH, SELECTION, TRANSFORM, vector3 as _vec3
from .materials import MATERIAL
from .nodes import REQUIRED, Named, Table, Value, Variant, reference_markdown as _markdown
from .solver_schema import SOLVER


PART = Table("a solid part", {
    "mesh": MESH,
    "material": Value("str", "name of the material of the part's cells"),
    "region_materials": Value("table", "cell set name -> material name, overriding `material` "
                              "on those cells", {}),
    "sets": Named("named selections from geometry (mesh and generator sets are named too)",
                  SELECTION),
    "transform": TRANSFORM,
    "pieces": Value("int", "the components path (solver.reduction.method) reduces the part "
                    "in this many pieces, each on its own, coupled on the cuts between them by "
                    "the traces of their modes: for a part too large for one worker's memory",
                    1, minimum=1, maximum=64),
})

CONSTRAINT = Table("zero displacement of the nodes of a selection", {
    "set": Value("str", "selection as PART.SET"),
    "dofs": Value("strs", "clamped directions", ["x", "y", "z"], choices=("x", "y", "z")),
})

def _signal_variant():
    """The `signal` table of a load, from the signals module's fields."""
    from .signals import SIGNAL_DOC, SIGNAL_FIELDS
    options = {}
    for kind, fields in SIGNAL_FIELDS.items():
        options[kind] = {key: Value(typ, doc, REQUIRED if default is None else default,
                                    "" if unit == "-" else unit)
                         for key, (typ, default, unit, doc) in fields.items()}
    return Variant(SIGNAL_DOC + " (constant: the preload, in equilibrium at t = 0)", options,
                   default="constant")


SIGNAL = _signal_variant()

LOAD = Variant("load: its nodal forces times its time signal", {
    "pressure": {
        "set": Value("str", "face selection as PART.SET"),
        # bounds far beyond any material's strength, that keep the products of the preload
        # (norms, energies) finite: 1e300 overflowed in them with warnings
        "value": Value("float", "pressure, positive when pushing into the surface", unit="Pa",
                       minimum=-1e12, maximum=1e12),
        "signal": SIGNAL,
    },
    "force": {
        "part": Value("str", "part carrying the force"),
        "point": _vec3("the force goes to the node nearest this point"),
        "vector": Value("floats", "force", unit="N", length=3, minimum=-1e15, maximum=1e15),
        "signal": SIGNAL,
    },
    "gravity": {
        "vector": Value("floats", "acceleration of gravity", unit="m/s^2", length=3,
                        minimum=-1e9, maximum=1e9),
        "parts": Value("strs", "parts it applies to (empty: all)", []),
        "signal": SIGNAL,
    },
})

CONTACT = Table("a contact pair: two face sets of two parts, gap observed on the fine rule or a "
                "coarser one, optionally regularized by the (1-eps)-compatible shapes", {
    "surface1": Value("str", "first surface as PART.SET (the gap is positive when it lies "
                      "outside part 2)"),
    "surface2": Value("str", "second surface as PART.SET; its outward normal is the contact "
                      "normal ('' with a wall)", ""),
    "wall_point": Value("floats", "a point of a rigid plane wall replacing surface 2 ([] : no "
                        "wall)", [], "m"),
    "wall_normal": Value("floats", "normal of the wall, pointing out of it towards surface 1",
                         [0.0, 0.0, 1.0], length=3),
    "law": Table("contact law of the transient (p >= 0 as a function of the gap g)", {
        "kind": Value("choice", "exponential p0 exp(-lambda g) with a linear continuation, "
                      "linear (unilateral penalty k max(-g, 0)) or bilateral (tied, -k g)",
                      "linear", choices=("exponential", "linear", "bilateral")),
        "p0": Value("float", "exponential: pressure at zero gap", 1e4, "Pa", open_min=0.0),
        "lambda": Value("float", "exponential: decay rate (tangent at pressure p: lambda p)",
                        5e5, "1/m", open_min=0.0),
        "p_lin": Value("float", "exponential: pressure beyond which the law continues linearly "
                       "(no overflow at any penetration)", 1e9, "Pa", open_min=0.0),
    }, optional=True),
    "order": Value("int", "degree of the Gauss rules: the fine rule's on Gamma's triangles, "
                   "the gauss rule's on each master face (4: 6 points on a triangle)", 4,
                   minimum=1, maximum=20),
    "k": Value("float", "stiffness density of the gap energy and of linear penalty contact",
               5e11, "Pa/m", open_min=0.0),
    "rule": Value("choice", "contact points: fine (the exact rule on Gamma), centre (one "
                  "point per face of the master surface), gauss (the Gauss points of each "
                  "master face, of degree order: the paper's rich rule), greedy (a coarse rule "
                  "selected on the regularized observation) or sampled (the fewest fine points "
                  "whose weights reproduce the contact stiffness that the reduced model's modes "
                  "below fmax see, and the preload: ECSW on the contact-linearized dynamics; "
                  "needs solver.reduction)", "fine",
                  choices=("fine", "centre", "gauss", "greedy", "sampled")),
    "candidates": Value("choice", "greedy: candidate points, the fine points or the face "
                        "centres of a surface", "fine", choices=("fine", "surface1", "surface2")),
    "points": Value("int", "greedy: number of points m (0: the rank of the kept shapes; more "
                    "restarts the selection); sampled: at most this many (0: no cap)", 0,
                    minimum=0),
    "sampling_tolerance": Value("float", "sampled: relative residual of the contact stiffness "
                                "and preload force reproduced; it sets the number of points "
                                "(pad_disc: 1e-2 gives 421 of 7734 points, histories within "
                                "0.4%)", 1e-2, open_min=0.0, maximum=1.0),
    "tolerance": Value("float", "greedy: stop when the largest remaining row norm falls below "
                       "this fraction of the largest", 1e-8, open_min=0.0, maximum=1.0),
    "weights": Value("choice", "greedy: nearest (each fine weight to its nearest point: exact "
                     "area, best tied frequencies), nnls (non-negative least squares on the gap "
                     "energy of the kept subspace and the area), best (the lower energy error of "
                     "the two) or exact (NNLS over all candidates: the energy reproduced exactly, "
                     "with as many points as needed; small interfaces only)", "nearest",
                     choices=("nearest", "nnls", "best", "exact")),
    "master": Value("choice", "surface whose faces carry the centre and gauss rules",
                    "surface1",
                    choices=("surface1", "surface2")),
    "regularized": Value("bool", "observe the gap through the (1-eps)-compatible shapes only",
                         False),
    "eps": Value("eps", "compatibility tolerance: shapes with sigma_i / max sigma <= eps are "
                 "kept; \"auto\" puts it in the largest jump of the spectrum", "auto",
                 minimum=0.0, maximum=1.0),
    "formulation": Value("choice", "dual (regularized gap observation, eq. 15) or primal "
                         "(interface dofs replaced by the kept shapes, eq. 11)", "dual",
                         choices=("dual", "primal")),
    "project": Value("choice", "dual: surfaces whose displacement is projected", "both",
                     choices=("both", "surface1", "surface2")),
    "norm": Value("choice", "norm of the pseudo-inverse of the dual projection: mass "
                  "(interface mass C^T W C) or identity (the paper's)", "mass",
                  choices=("mass", "identity")),
    "friction": Table("Coulomb friction along the sliding that a [motion] of one of the two "
                      "parts imposes: traction mu p times the regularized sign of the sliding "
                      "velocity, observed through the same rule (and regularization) as the "
                      "gap", {
        "mu": Value("float", "friction coefficient (0: no friction; with a speeds table, "
                    "leave it 0)", 0.0, minimum=0.0, maximum=10.0),
        "speeds": Value("floats", "sliding speeds of a table mu(v), increasing, >= 0 (a "
                        "falling characteristic; constant beyond its ends)", [], "m/s",
                        minimum=0.0),
        "values": Value("floats", "friction coefficients at those speeds", [], minimum=0.0,
                        maximum=10.0),
        "regularization": Value("choice", "smooth sign of the sliding velocity v: tanh(v / "
                                "v_eps) (the default: exactly Coulomb once v > 20 v_eps) or "
                                "atan ((2 / pi) atan(v / v_eps): a tail of 2 v_eps / (pi v) "
                                "below Coulomb at any speed)", "tanh",
                                choices=("tanh", "atan")),
        "v_eps": Value("float", "slip velocity of the regularization: the law's slope at rest "
                       "is mu p w / v_eps, a viscous damper that bounds an explicit step",
                       1e-3, "m/s", open_min=0.0),
        "basis_mu": Value("float", "friction coefficient the reduced basis is built at, then "
                          "given the case's preload: a friction sweep's variants share it "
                          "(transient sweep); 0: mu", 0.0, minimum=0.0, maximum=10.0),
    }, optional=True),
})

MOTION = Variant("rigid motion imposed on a part's material (its mesh stays: the sliding seen "
                 "by the contact, as a disc rotating under a pad; no inertial terms of the "
                 "motion are added)", {
    "rotation": {
        "part": Value("str", "part set in rotation"),
        "axis": Value("floats", "direction of the axis (right-handed with omega)", length=3),
        "point": _vec3("a point of the axis"),
        "omega": Value("float", "angular speed", unit="rad/s", minimum=-1e6, maximum=1e6),
    },
    "translation": {
        "part": Value("str", "part moving (a belt)"),
        "velocity": Value("floats", "velocity", unit="m/s", length=3, minimum=-1e6,
                          maximum=1e6),
    },
})

SENSOR = Table("displacement observed at a point", {
    "part": Value("str", "part observed"),
    "point": _vec3("the node nearest this point is observed"),
    "direction": Value("floats", "direction observed", [0.0, 0.0, 1.0], length=3),
})

OUTPUT = Table("outputs", {
    "vtu": Value("str", "write the model (and modes) to this VTU file, relative to the case "
                 "file ('' = none); `transient cea` writes its complex modes beside it, a "
                 "NAME_mode_NNN.vtu and .pvd per mode and NAME_modes.csv", ""),
    "file": Value("str", "HDF5 history of `transient run`, relative to the case file ('': the "
                  "case's name with .h5)", ""),
    "every": Value("int", "store one step in this many", 1, minimum=1),
    "sensors": Value("bool", "store the sensors' histories", True),
    "contact": Value("bool", "store gap and pressure at the contact points, and with "
                     "friction their slip velocities along and across the sliding", False),
    "energy": Value("bool", "store the energy balance terms (always computed: the run "
                    "checks the balance)", True),
    "field": Value("bool", "store the state q every `every` steps (reduced coordinates, or "
                   "the free dofs of the full model) so `transient export` can write the "
                   "displacement field", False),
}, optional=True)

CEA = Table("complex eigenvalue analysis (`transient cea`): what is called unstable, and which "
            "modes are described and written", {
    "threshold": Table("the growth a mode must exceed to be called unstable", {
        "growth_rate": Value("float", "real part of the eigenvalue, the mode's growth rate "
                             "(its amplitude grows as exp(growth_rate t)), above which a mode is "
                             "unstable in the table, the CSV, the JSON and the pictures; a "
                             "damping ratio below -1e-6 is needed too (round-off: 0 keeps that "
                             "alone)", 0.0, "1/s", minimum=0.0, maximum=1e12),
    }, optional=True),
    "shapes": Value("choice", "the modes described (kinetic energy shares, nodal diameters, "
                    "part modes, residual) and written for ParaView with output.vtu: the "
                    "unstable ones, or all below the band's top", "unstable",
                    choices=("unstable", "all")),
}, optional=True)

LIMITS = Table("bounds on the work of a case, checked before it starts (raise them to go "
               "beyond)", {
    "memory": Value("float", "memory the model and its setup may take, estimated from the "
                    "cells before any is meshed (0: the machine's physical memory)", 0.0, "GB",
                    minimum=0.0),
    "steps": Value("int", "time steps a run may make", 100_000_000, minimum=1),
    "part_span": Value("float", "the largest span a file mesh read at scale 1 may have: "
                       "beyond it its coordinates are taken for millimetres read as metres",
                       10.0, "m", minimum=0.0),
}, optional=True)

INITIAL = Table("initial velocity of a part (impact)", {
    "part": Value("str", "part set in motion"),
    "velocity": Value("floats", "velocity", unit="m/s", length=3, minimum=-1e6, maximum=1e6),
})

CASE = Table("a case", {
    "title": Value("str", "one-line description", ""),
    "materials": Named("materials by name", MATERIAL, min_items=1),
    "parts": Named("parts by name", PART, min_items=1),
    "constraints": Named("constraints by name", CONSTRAINT),
    "loads": Named("loads by name", LOAD),
    "contact": Named("contact pairs by name", CONTACT),
    "sensors": Named("sensors by name", SENSOR),
    "initial": Named("initial velocities by name", INITIAL),
    "motion": Named("rigid motions imposed on parts by name (the sliding of friction)", MOTION),
    "solver": SOLVER,
    "output": OUTPUT,
    "cea": CEA,
    "limits": LIMITS,
})


def reference_markdown():
    """The key table of cases/README.md."""
    return _markdown(CASE)
