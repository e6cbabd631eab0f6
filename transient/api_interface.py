"""The public API on a contact interface: `transient.compat` (one pair's compatibility: the gap
energy's spectrum and C(eps)) and `compat_pairs` (several pairs of a case on one model, as
`transient plot compat` draws them)."""
import time
from dataclasses import dataclass

from .case.checks import check_two_surfaces
from .errors import CaseError


@dataclass(frozen=True)
class InterfaceCompatibility:
    """The compatibility of a contact pair's interface (`compat`)."""
    pair: object             # contact.pair.ContactPair: its rules, eps and coarse rule
    compatibility: object    # contact.compatibility.Compatibility: sigma, shapes, C(eps)
    setup_s: float           # the pair's stages [s]
    timings: dict            # stage -> seconds

    def summary(self, eps_grid):
        """What ``transient compat --json`` prints (C(eps) on eps_grid), but for the total
        time."""
        comp, fine, pair = self.compatibility, self.pair.interface.fine, self.pair
        coarse = pair.coarse
        return {"pair": pair.name, "n_points": fine.n_points, "area": fine.area,
                "n_dof_1": comp.n1, "n_dof_2": comp.n2, "sigma_max": float(comp.sigma.max()),
                "singular_values": comp.normalized.tolist(),
                "compatibility": {"eps": list(map(float, eps_grid)),
                                  "C": comp.curve(eps_grid).tolist()},
                "eps": pair.eps, "eps_source": pair.eps_source, "kept": comp.kept(pair.eps),
                "coarse": None if coarse is None else {
                    "m": len(coarse.chosen), "energy_error": coarse.energy_error,
                    "setup_s": pair.timings["coarse_rule"], "rank": coarse.rank,
                    "weighting": coarse.weighting, "area_error": coarse.area_error},
                "setup_s": self.setup_s, "timings": dict(self.timings)}


def compat(case, pair=None):
    """Compatibility of a contact pair's interface: the gap energy's spectrum and C(eps).

    Parameters
    ----------
    case : Case
        From `load`.
    pair : str, optional
        The pair's name (``[contact.NAME]``); by default the case's first.

    Returns
    -------
    InterfaceCompatibility
        ``compatibility`` (``sigma`` ascending [N/m], ``normalized``, the interface
        ``shapes``, ``kept(eps)`` and ``curve(eps)`` = C(eps)), ``pair`` (its fine rule, its
        ``eps`` and the greedy rule when the case asks for one), ``setup_s`` and ``timings``
        [s].
    """
    return compat_pairs(case, [pair_name(case, pair)])[0]


def compat_pairs(case, pairs=None):
    """Compatibility of several contact pairs of a case, their model built once.

    Every pair named is checked before the model is built.

    Parameters
    ----------
    case : Case
        From `load`.
    pairs : sequence of str, optional
        The pairs' names; by default every pair of the case.

    Returns
    -------
    list of InterfaceCompatibility
        One per pair, in the case's order, as `compat` returns it (none for no names).
    """
    from .contact.pair import build_pair
    from .model.model import build_model
    names = list(case.contact)
    if not names:
        raise CaseError(case.path, "contact", "the case has no [contact.NAME] pair")
    for name in pairs or ():
        if name not in names:
            raise CaseError(case.path, "contact", f"no pair '{name}' (pairs: "
                            f"{', '.join(names)})")
    chosen = [n for n in names if pairs is None or n in pairs]
    for name in chosen:
        check_two_surfaces(case, name)
    if not chosen:
        return []
    model = build_model(case)
    out = []
    for name in chosen:
        t0 = time.perf_counter()
        built = build_pair(case, model, name, need_compatibility=True)
        setup = time.perf_counter() - t0
        comp = built.compat
        out.append(InterfaceCompatibility(built, comp, setup, {
            **model.timings, **built.timings, **built.interface.timings, **comp.timings}))
    return out


def pair_name(case, pair=None):
    """The contact pair a command names (the case's first by default), checked to exist."""
    names = list(case.contact)
    if not names:
        raise CaseError(case.path, "contact", "the case has no [contact.NAME] pair")
    if not pair:
        return names[0]
    if pair not in names:
        raise CaseError(case.path, "contact", f"no pair '{pair}' (pairs: {', '.join(names)})")
    return pair
