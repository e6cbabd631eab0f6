"""Frozen specs of a case, built once from the validated tables: the stages read these, never
the raw TOML dict. Field names are the case keys ("lambda", a Python keyword, becomes `lam`);
units SI as in the schema. Tables keyed by name become dicts of specs in file order.
"""
import os
from dataclasses import dataclass, fields

SHIFT_HZ = 1.0     # -(2 pi SHIFT_HZ)^2 shifts K so that floating parts stay solvable
# The reduced basis' normal modes reach CUTOFF_FACTOR times the band (reduction.fmax) by
# default: the friction couples each mode of the band with the modes above it, and the
# coupled modes' real parts converge only once those are held (studies/study_cea_band.py)
CUTOFF_FACTOR = 2.0


@dataclass(frozen=True)
class OrientationSpec:
    kind: str                # global, rectangular, cylindrical (case.materials)
    a: tuple = ()            # rectangular: the 1-axis, and
    b: tuple = ()            # a direction of the 1-2 plane
    point: tuple = ()        # cylindrical: a point of the axis [m], and
    axis: tuple = ()         # its direction, the 3-axis


@dataclass(frozen=True)
class MaterialSpec:
    rho: float               # [kg/m^3]
    E: float = 0.0           # isotropic [Pa]
    nu: float = 0.0
    elasticity: str = "isotropic"   # or transversely_isotropic, orthotropic
    constants: tuple = ()    # the anisotropic ones: (key, value) pairs, SI (case.materials)
    orientation: OrientationSpec = OrientationSpec("global")
    loss_factor: float = 0.0


def _material(table):
    """The MaterialSpec of a validated material table."""
    common = ("rho", "E", "nu", "elasticity", "orientation", "loss_factor")
    return _make(MaterialSpec, {k: v for k, v in table.items() if k in common},
                 orientation=_make(OrientationSpec, table["orientation"]),
                 constants=tuple((k, v) for k, v in table.items() if k not in common))


@dataclass(frozen=True)
class MeshSpec:
    kind: str                # a generator of mesh.generators, or "file"
    params: dict             # the generator's arguments, or path, scale, translate


@dataclass(frozen=True)
class SelectionSpec:
    kind: str                # plane, box, cylinder
    params: dict             # point, normal, min, max, axis, radius, tol


@dataclass(frozen=True)
class RotationSpec:
    axis: tuple              # () when no angle needs one
    angle: float             # [deg]
    point: tuple             # [m]


@dataclass(frozen=True)
class MirrorSpec:
    point: tuple             # [m]
    normal: tuple            # (): no mirror


@dataclass(frozen=True)
class TransformSpec:
    """A part's placement: translate, then rotate, then mirror (mesh.placement)."""
    translate: tuple         # [m]
    rotate: RotationSpec
    mirror: MirrorSpec


@dataclass(frozen=True)
class PartSpec:
    mesh: MeshSpec
    material: str
    region_materials: dict   # cell set -> material name
    sets: dict               # name -> SelectionSpec
    transform: TransformSpec
    pieces: int = 1          # the components path's pieces of the part (reduce.pieces)


@dataclass(frozen=True)
class ConstraintSpec:
    set: str
    dofs: tuple


@dataclass(frozen=True)
class LoadSpec:
    kind: str                # pressure, force, gravity
    signal: dict             # kind and that kind's keys (case.signals)
    set: str = ""
    value: float = 0.0
    part: str = ""
    point: tuple = ()
    vector: tuple = ()
    parts: tuple = ()


@dataclass(frozen=True)
class LawSpec:
    kind: str
    p0: float
    lam: float
    p_lin: float


@dataclass(frozen=True)
class FrictionSpec:
    mu: float
    speeds: tuple            # a table mu(v) when given [m/s]
    values: tuple
    regularization: str      # tanh, atan
    v_eps: float             # [m/s]
    basis_mu: float = 0.0    # the reduced basis' friction coefficient; 0: mu's

    @property
    def active(self):
        return self.mu > 0.0 or any(v > 0.0 for v in self.values)


@dataclass(frozen=True)
class MotionSpec:
    kind: str                # rotation, translation
    part: str
    axis: tuple = ()
    point: tuple = ()
    omega: float = 0.0       # [rad/s]
    velocity: tuple = ()     # [m/s]


@dataclass(frozen=True)
class ContactSpec:
    name: str
    surface1: str
    surface2: str
    wall_point: tuple
    wall_normal: tuple
    law: LawSpec
    order: int
    k: float
    rule: str
    candidates: str
    points: int
    sampling_tolerance: float
    tolerance: float
    weights: str
    master: str
    regularized: bool
    eps: object              # float or "auto"
    formulation: str
    project: str
    norm: str
    friction: FrictionSpec

    @property
    def wall(self):
        return bool(self.wall_point)


@dataclass(frozen=True)
class SensorSpec:
    part: str
    point: tuple
    direction: tuple


@dataclass(frozen=True)
class InitialSpec:
    part: str
    velocity: tuple


@dataclass(frozen=True)
class ModesSpec:
    count: int
    fmax: float
    shift: float
    tie: str


@dataclass(frozen=True)
class DampingSpec:
    modal: float
    residual: float
    alpha: float
    beta: float
    loss_frequency: float = 0.0   # [Hz] the materials' loss as viscous damping; 0: fmax


@dataclass(frozen=True)
class ReductionSpec:
    enabled: bool
    fmax: float
    statics: bool
    statics_tolerance: float
    mass_scaling_hz: float = 0.0
    cutoff: float = 0.0
    method: str = "assembled"

    @property
    def modes_fmax(self):
        """The basis' normal modes reach this frequency [Hz]: the cutoff given, or
        CUTOFF_FACTOR times the band."""
        return self.cutoff or CUTOFF_FACTOR * self.fmax

    @property
    def components(self):
        """Whether the model is reduced part by part (reduce.components): a reduced model
        whose method is "components"."""
        return self.enabled and self.method == "components"


@dataclass(frozen=True)
class NewtonSpec:
    tolerance: float
    max_iter: int


@dataclass(frozen=True)
class QuadratureSpec:
    stiffness: int
    mass: int


@dataclass(frozen=True)
class SolverSpec:
    modes: ModesSpec
    scheme: str
    corrections: int
    corrector: str
    t_end: float
    mass: str
    dt: float
    force_dt: bool
    chunk: int
    drift_tolerance: float
    subdivision: int
    damping: DampingSpec
    reduction: ReductionSpec
    newton: NewtonSpec
    linear_solver: str
    quadrature: QuadratureSpec
    shift_hz: float = SHIFT_HZ

    @property
    def lumped(self):
        """The transient's mass is the lumped one (auto: for central differences on the full
        model, which need it diagonal)."""
        return self.mass == "lumped" or (self.mass == "auto" and self.scheme == "explicit"
                                         and not self.reduction.enabled)


@dataclass(frozen=True)
class LimitsSpec:
    memory: float            # [GB], 0: the machine's physical memory
    steps: int
    part_span: float = 10.0  # [m]

    @property
    def memory_bytes(self):
        return self.memory * 1e9 if self.memory > 0 else physical_memory()


def physical_memory():
    """The machine's physical memory [B]."""
    return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))


@dataclass(frozen=True)
class OutputSpec:
    vtu: str
    file: str
    every: int
    sensors: bool
    contact: bool
    energy: bool
    field: bool


@dataclass(frozen=True)
class CeaSpec:
    growth_rate: float       # [1/s] above which a mode is unstable (cea.threshold)
    shapes: str              # unstable, all: the modes described and written


def _plain(value):
    """Lists as tuples: a spec's values do not change."""
    return tuple(_plain(v) for v in value) if isinstance(value, list) else value


def _make(cls, table, **given):
    """cls from a validated table (every key case/schema.py declares there, defaults filled)
    and the nested specs given. A key the dataclass lacks is a schema key no stage would
    ever read: an error here, at the first load, not a setting silently ignored."""
    names = {f.name for f in fields(cls)}
    values = {("lam" if k == "lambda" else k): _plain(v) for k, v in table.items()}
    values.update(given)
    lost = sorted(set(values) - names)
    if lost:
        raise TypeError(f"{cls.__name__} has no field for the case key(s) {', '.join(lost)} "
                        "that case/schema.py declares")
    return cls(**values)


def _variant(cls, table):
    return cls(table["kind"], {k: _plain(v) for k, v in table.items() if k != "kind"})


def _transform(table):
    return TransformSpec(_plain(table["translate"]), _make(RotationSpec, table["rotate"]),
                         _make(MirrorSpec, table["mirror"]))


def build(data):
    """The specs of a validated case dict: name -> spec (or dict of specs)."""
    solver = data["solver"]
    return {
        "title": data["title"],
        "materials": {n: _material(t) for n, t in data["materials"].items()},
        "parts": {n: PartSpec(_variant(MeshSpec, t["mesh"]), t["material"],
                              dict(t["region_materials"]),
                              {s: _variant(SelectionSpec, v) for s, v in t["sets"].items()},
                              _transform(t["transform"]), t["pieces"])
                  for n, t in data["parts"].items()},
        "constraints": {n: _make(ConstraintSpec, t) for n, t in data["constraints"].items()},
        "loads": {n: _make(LoadSpec, t, signal=dict(t["signal"]))
                  for n, t in data["loads"].items()},
        "contact": {n: _make(ContactSpec, t, name=n, law=_make(LawSpec, t["law"]),
                             friction=_make(FrictionSpec, t["friction"]))
                    for n, t in data["contact"].items()},
        "motion": {n: _make(MotionSpec, t) for n, t in data["motion"].items()},
        "sensors": {n: _make(SensorSpec, t) for n, t in data["sensors"].items()},
        "initial": {n: _make(InitialSpec, t) for n, t in data["initial"].items()},
        "solver": _make(SolverSpec, solver, modes=_make(ModesSpec, solver["modes"]),
                        damping=_make(DampingSpec, solver["damping"]),
                        reduction=_make(ReductionSpec, solver["reduction"]),
                        newton=_make(NewtonSpec, solver["newton"]),
                        quadrature=_make(QuadratureSpec, solver["quadrature"])),
        "output": _make(OutputSpec, data["output"]),
        "cea": CeaSpec(data["cea"]["threshold"]["growth_rate"], data["cea"]["shapes"]),
        "limits": _make(LimitsSpec, data["limits"]),
    }
