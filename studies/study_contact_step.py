"""Where an explicit penalty impact conserves energy: the energy error of a bar hitting a rigid
wall against omega_c dt, the contact oscillator's frequency times the step.

omega_c is the highest frequency of the penalties alone on the lumped mass
(`CriticalStep.omega_contact`: M^-1/2 C^T diag(w k) C M^-1/2), the contact oscillator of the
end face. Central differences
are stable for the whole system below omega_max dt = 2, but an impact is not a linear
oscillation: the contact opens and closes between steps, each chatter of the end face injects or
removes energy, and near the limit it gains it (an aluminium bar at k = 2e14, issue 13: 0.84 J
grew to 10 J). This study runs cases/bar_impact.toml (steel) and the same bar in aluminium
over element sizes, penalties k, steps dt (fractions of the critical step) and wall offsets (the phase at
which the first contact step lands), and prints the worst energy drift per omega_c dt bin,
the figure behind `dynamics.critical.CONTACT_OMEGA_DT`.

    python studies/study_contact_step.py [--quick] [--json]
"""
import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from transient.case.loading import load                        # noqa: E402
from transient.dynamics.energy import drift                    # noqa: E402
from transient.kernels.codes import ENERGY_TERMS               # noqa: E402
from transient.stages import prepare, simulate                 # noqa: E402

CASE = ROOT / "cases" / "bar_impact.toml"
MATERIALS = {"steel": [], "aluminium": ["materials.steel.E=7.0e10", "materials.steel.rho=2700.0"]}


def impact(material, divisions, k, fraction, offset):
    """(omega_c dt, omega_max dt, drift) of one impact lasting past the rebound."""
    sets = MATERIALS[material] + [f"contact.wall.k={k!r}",
                                  f"parts.bar.mesh.divisions=[{divisions},1,1]",
                                  f"contact.wall.wall_point=[{0.1 + offset!r}, 0.0, 0.0]"]
    case = load(CASE, sets)
    setup = prepare(case)
    critical = setup.system.critical
    dt = fraction * critical.dt
    c = np.sqrt(case.materials["steel"].E / case.materials["steel"].rho)
    t_end = offset / 1.0 + 2 * 0.1 / c + 4e-5    # first touch, 2 L / c of contact, the rebound
    series, status, _ = simulate(case, setup, dt, int(t_end / dt))
    d = drift({t: series[f"energy/{t}"] for t in ENERGY_TERMS}) if status == "complete" \
        else np.inf
    return critical.omega_contact * dt, 2.0 * dt / critical.dt, d


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a few points per axis")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    ks = [5e13, 2e14, 8e14] if args.quick else [2e13, 1e14, 2e14, 5e14, 2e15]
    fractions = [0.5, 0.9] if args.quick else [0.4, 0.6, 0.8, 0.9, 0.99]
    offsets = [1e-5, 1.0037e-5] if args.quick else [1e-5, 1.0029e-5, 1.0071e-5]
    divisions = [100, 25] if args.quick else [100, 40, 16]
    rows = []
    for material, n, k, fraction in ((m, n, k, f) for m in MATERIALS for n in divisions
                                     for k in ks for f in fractions):
        worst = max((impact(material, n, k, fraction, o) for o in offsets), key=lambda r: r[2])
        rows.append({"material": material, "divisions": n, "k": k, "fraction": fraction,
                     "omega_c_dt": worst[0], "omega_max_dt": worst[1], "drift": worst[2]})
        if not args.json:
            print(f"{material:9s} {n:3d} el.  k {k:8.2e}  dt/crit {fraction:4.2f}  "
                  f"omega_c dt {worst[0]:5.3f}  omega_max dt {worst[1]:5.3f}  "
                  f"drift {worst[2]:9.2e}", flush=True)
    if args.json:
        print(json.dumps(rows))
        return
    print("\nworst drift by omega_c dt:")
    edges = np.arange(0.0, 2.01, 0.1)
    for lo, hi in zip(edges[:-1], edges[1:]):
        inside = [r["drift"] for r in rows if lo <= r["omega_c_dt"] < hi]
        if inside:
            print(f"  [{lo:3.1f}, {hi:3.1f})  {max(inside):9.2e}  ({len(inside)} runs)")


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
