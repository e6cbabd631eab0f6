"""Checks that need several keys of a case, run at load: before any mesh is built, a wrong
combination is a one-line error naming the key to change."""
from ..errors import CaseError
from .auto import choose_method
from .materials import check_materials
from .signals import check_signal
from .sizes import check_generated, check_steps


def check(case):
    """Raise CaseError on the first combination of keys that no stage admits (every case);
    return the case, its reduction's method chosen where it says "auto" (case/auto.py)."""
    _references(case)
    check_materials(case)
    _contact(case)
    _friction(case)
    _signals(case)
    _directions(case)
    _mass_scaling(case)
    case = choose_method(case)
    _pieces(case)
    _components(case)
    check_generated(case)
    return case


def check_transient(case):
    """Raise CaseError on the first combination of keys the transient stages would refuse:
    run by the commands that integrate in time, before their first stage."""
    _sampled(case)
    _solver(case)
    if case.solver.t_end <= 0.0:
        _fail(case, "solver.t_end", "expected > 0 for a transient: the time simulated after "
              "the preload")
    if case.solver.dt > 0.0:
        check_steps(case, case.solver.dt)


def _fail(case, key, message):
    raise CaseError(case.path, key, message)


def _part_of(ref):
    return ref.split(".", 1)[0] if isinstance(ref, str) and "." in ref else None


def _known(case, key, name, names, what):
    if name not in names:
        _fail(case, key, f"unknown {what} '{name}' ({what}s: {', '.join(names) or 'none'})")


def _references(case):
    """Parts and materials named by other tables exist (sets need the meshes: model stage)."""
    parts = list(case.parts)
    for name, part in case.parts.items():
        _known(case, f"parts.{name}.material", part.material, list(case.materials), "material")
        for cset, material in part.region_materials.items():
            _known(case, f"parts.{name}.region_materials.{cset}", material,
                   list(case.materials), "material")
    refs = [(f"constraints.{n}.set", c.set) for n, c in case.constraints.items()]
    refs += [(f"loads.{n}.set", s.set) for n, s in case.loads.items() if s.kind == "pressure"]
    refs += [(f"contact.{n}.surface1", c.surface1) for n, c in case.contact.items()]
    refs += [(f"contact.{n}.surface2", c.surface2) for n, c in case.contact.items()
             if c.surface2]
    for key, ref in refs:
        part = _part_of(ref)
        if part is None:
            _fail(case, key, f"expected PART.SET, got '{ref}'")
        _known(case, key, part, parts, "part")
    for name, load in case.loads.items():
        if load.kind == "force":
            _known(case, f"loads.{name}.part", load.part, parts, "part")
        for p in load.parts if load.kind == "gravity" else ():
            _known(case, f"loads.{name}.parts", p, parts, "part")
    for name, sensor in case.sensors.items():
        _known(case, f"sensors.{name}.part", sensor.part, parts, "part")
    for name, initial in case.initial.items():
        _known(case, f"initial.{name}.part", initial.part, parts, "part")
    moved = {}
    for name, motion in case.motion.items():
        _known(case, f"motion.{name}.part", motion.part, parts, "part")
        if motion.part in moved:
            _fail(case, f"motion.{name}.part", f"part '{motion.part}' already moves by "
                  f"motion.{moved[motion.part]}: one motion per part")
        moved[motion.part] = name


def check_two_surfaces(case, name):
    """Compatibility (transient compat, plot compat) is between two meshes: not a wall's."""
    if case.contact[name].wall:
        _fail(case, f"contact.{name}.wall_point", "a rigid wall has no second mesh: "
              "compatibility is between two surfaces")


def _signals(case):
    """Each load's signal within its kind's bounds (durations > 0, increasing tables)."""
    for name, load in case.loads.items():
        try:
            check_signal(load.signal, f"loads.{name}.signal")
        except ValueError as exc:
            key, _, message = str(exc).partition(": ")
            _fail(case, key, message)


def _directions(case):
    """Normals, axes and directions that must have a length; a part rotated by an angle needs
    the axis of its rotation."""
    vectors = [(f"contact.{n}.wall_normal", c.wall_normal) for n, c in case.contact.items()
               if c.wall]
    vectors += [(f"sensors.{n}.direction", s.direction) for n, s in case.sensors.items()]
    vectors += [(f"motion.{n}.axis", m.axis) for n, m in case.motion.items()
                if m.kind == "rotation"]
    for part, spec in case.parts.items():
        for name, sel in spec.sets.items():
            for field in ("normal", "axis"):
                if field in sel.params:
                    vectors.append((f"parts.{part}.sets.{name}.{field}", sel.params[field]))
        rotate, mirror = spec.transform.rotate, spec.transform.mirror
        key = f"parts.{part}.transform"
        if rotate.angle != 0.0 and not rotate.axis:
            _fail(case, f"{key}.rotate.axis", f"missing: a rotation of {rotate.angle:g} deg "
                  "needs its axis")
        vectors += [(f"{key}.rotate.axis", rotate.axis)] if rotate.axis else []
        vectors += [(f"{key}.mirror.normal", mirror.normal)] if mirror.normal else []
    for key, v in vectors:
        if not any(x != 0.0 for x in v):
            _fail(case, key, "expected a nonzero vector")


def _contact(case):
    for name, c in case.contact.items():
        key = f"contact.{name}"
        if c.wall:
            if len(c.wall_point) != 3 or c.surface2:
                _fail(case, f"{key}.wall_point", "a wall takes a point [x, y, z] and no "
                      "surface2")
            if c.regularized or c.rule not in ("fine", "sampled"):
                _fail(case, f"{key}.rule", "a rigid wall is observed by the fine rule, or "
                      "points sampled from it, unregularized (no second mesh to be "
                      "compatible with)")
        else:
            if not c.surface2:
                _fail(case, f"{key}.surface2", "missing: a second surface as PART.SET, or a "
                      "wall_point")
            if _part_of(c.surface1) == _part_of(c.surface2):
                _fail(case, f"{key}.surface2", "both surfaces belong to the same part")
        if c.rule == "greedy" and not c.regularized:
            _fail(case, f"{key}.regularized", "the greedy rule selects points on the "
                  "regularized observation: set regularized = true")


def _friction(case):
    """A friction table is well formed, and friction has a sliding to act along."""
    moving = {m.part for m in case.motion.values()
              if any(x != 0.0 for x in (m.velocity if m.kind == "translation" else (m.omega,)))}
    for name, c in case.contact.items():
        f, key = c.friction, f"contact.{name}.friction"
        if len(f.values) != len(f.speeds):
            _fail(case, f"{key}.values", f"expected {len(f.speeds)} values, one per speed of "
                  f"{key}.speeds, got {len(f.values)}")
        if f.speeds:
            if any(b <= a for a, b in zip(f.speeds, f.speeds[1:])):
                _fail(case, f"{key}.speeds", "expected increasing speeds")
            if f.mu != 0.0:
                _fail(case, f"{key}.mu", "give mu or the table speeds / values, not both")
        if f.basis_mu:
            if f.speeds:
                _fail(case, f"{key}.basis_mu", "a basis at another friction coefficient needs "
                      "a constant mu, not a table speeds / values")
            if not case.solver.reduction.enabled:
                _fail(case, f"{key}.basis_mu", "the basis is the reduced model's: set "
                      "solver.reduction.enabled = true")
        if not f.active and not f.basis_mu:
            continue
        parts = {_part_of(c.surface1)} | ({_part_of(c.surface2)} if not c.wall else set())
        if not parts & moving:
            _fail(case, f"{key}.{'mu' if f.active else 'basis_mu'}", "friction needs "
                  "sliding: no [motion] moves "
                  f"{' or '.join(sorted(parts))} (a rotation of the disc, a translation of "
                  "a belt)")


def _mass_scaling(case):
    reduction = case.solver.reduction
    cap = reduction.mass_scaling_hz
    if cap and not reduction.enabled:
        _fail(case, "solver.reduction.mass_scaling_hz", "mass scaling acts on the reduced "
              "model's statics: set solver.reduction.enabled = true")
    if cap and cap <= reduction.modes_fmax:
        _fail(case, "solver.reduction.mass_scaling_hz", f"{cap:g} Hz is not above the basis' "
              f"cutoff ({reduction.modes_fmax:g} Hz): only the statics, above the basis' "
              "modes, may take mass (0: no mass scaling)")
    if reduction.cutoff and reduction.cutoff < reduction.fmax:
        _fail(case, "solver.reduction.cutoff", f"{reduction.cutoff:g} Hz is below fmax "
              f"({reduction.fmax:g} Hz): the basis must hold the band's modes (0: 2 fmax)")


def _sampled(case):
    for name, c in case.contact.items():
        if c.rule == "sampled" and not case.solver.reduction.enabled:
            _fail(case, f"contact.{name}.rule", "the sampled rule picks its points on the "
                  "reduced model: set solver.reduction.enabled = true")


def _pieces(case):
    for name, part in case.parts.items():
        if part.pieces > 1 and not case.solver.reduction.components:
            _fail(case, f"parts.{name}.pieces", "the components path reduces a part in pieces: "
                  "set solver.reduction.enabled = true and solver.reduction.method = "
                  '"components"')


def _components(case):
    """The components path's part bases do not depend on the friction: a basis made at
    another friction (basis_mu) has nothing to share there."""
    if not case.solver.reduction.components or not rebased(case):
        return
    name = next(n for n, c in case.contact.items() if c.friction.basis_mu)
    auto = f" ({case.reduction_auto})" if case.reduction_auto else ""
    _fail(case, f"contact.{name}.friction.basis_mu", 'not with solver.reduction.method = '
          f'"components"{auto}, whose part bases do not depend on the friction: leave it out')


def rebased(case):
    """Whether the case's basis is made at another friction than its own (a pair's basis_mu
    differs from its mu), and is then rebased on its preload (reduce.reference)."""
    return any(c.friction.basis_mu and c.friction.basis_mu != c.friction.mu
               for c in case.contact.values())


def _solver(case):
    solver = case.solver
    reduced = solver.reduction.enabled
    if solver.scheme == "exponential" and not reduced:
        _fail(case, "solver.scheme", "the exponential scheme propagates the modes of a reduced "
              "model: set solver.reduction.enabled = true")
    if not reduced:
        if solver.damping.modal > 0:
            _fail(case, "solver.damping.modal", "modal damping needs the reduced model "
                  "(solver.reduction.enabled = true); use alpha and beta")
        lossy = [name for name, m in case.materials.items() if m.loss_factor > 0]
        if lossy:
            _fail(case, f"materials.{lossy[0]}.loss_factor", "a run takes the materials' loss "
                  "on the reduced model (solver.reduction.enabled = true), each vector's "
                  "share of it; the full model's cea takes it, its run does not: use beta")
        if solver.mass == "consistent" and solver.scheme == "explicit":
            _fail(case, "solver.mass", "central differences on the full model need the "
                  "lumped mass: use lumped (or auto), or a reduced model")
        if solver.scheme == "implicit" and solver.dt == 0.0:
            _fail(case, "solver.dt", "the implicit scheme on the full model has no frequency "
                  "to resolve: give dt")
