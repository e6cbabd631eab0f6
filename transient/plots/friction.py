"""The friction of a stored run: its powers in time, the share of the contact area open,
sticking and slipping, and the status map on Gamma at a time (`transient plot friction`)."""
import numpy as np

from ..contact.friction import STATUS_NAMES, contact_status, friction_powers
from .history import _figure, _suptitle, _title
from .pressure import contact_pair, plane_frame

COLOURS = ("#bbbbbb", "#1f77b4", "#d62728")     # open, stick, slip


def friction_series(stored, pair):
    """The pair's friction in time: {'time', 'input', 'dissipated' [W], 'shares' (rows, 3) of
    the contact area open, sticking and slipping, 'status' (rows, m), and the geometry},
    from its stored gaps, pressures and slips (output.contact = true with friction)."""
    pair = contact_pair(stored, pair)
    if f"contact/{pair}/slip" not in stored.series:
        raise stored.error(f"contact/{pair}/slip", "no slip velocities stored: a run with "
                           "friction and output.contact = true stores them")
    law = stored.friction_law(pair)
    if law is None:
        raise stored.error("system/contacts/friction", "no friction law stored with the "
                           "system")
    geometry = stored.contact_geometry(pair)
    gap, press = stored.read(f"contact/{pair}/gap"), stored.read(f"contact/{pair}/pressure")
    slip = stored.read(f"contact/{pair}/slip")
    p_in, p_diss = friction_powers(law, geometry["weights"], press, slip)
    status = contact_status(gap, slip, law[1])
    w = geometry["weights"]
    shares = np.stack([(w * (status == k)).sum(axis=1) for k in range(3)], axis=1) / w.sum()
    return {"pair": pair, "time": stored.time(), "input": p_in, "dissipated": p_diss,
            "shares": shares, "status": status, "slip": slip, **geometry}


def friction_figure(stored, series, path, time=None):
    """Three panels: the sliding's input and the slip's dissipation in time, the shares of
    the contact area by status, and the status map at `time` (default the last row)."""
    t = series["time"]
    row = len(t) - 1 if time is None else int(np.argmin(np.abs(t - time)))
    fig = _figure(13.0, 4.6)
    power, shares, where = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1.2, 1.2, 1.0]})
    power.plot(t * 1e3, series["input"], label="sliding's input")
    power.plot(t * 1e3, series["dissipated"], label="slip's dissipation")
    power.plot(t * 1e3, series["input"] - series["dissipated"], label="to the structure")
    power.set_xlabel("time [ms]")
    power.set_ylabel("power [W]")
    power.legend(fontsize=8)
    for k, name in enumerate(STATUS_NAMES):
        shares.plot(t * 1e3, 100 * series["shares"][:, k], color=COLOURS[k], label=name)
    shares.axvline(t[row] * 1e3, color="black", lw=0.5)
    shares.set_xlabel("time [ms]")
    shares.set_ylabel("share of the contact area [%]")
    shares.set_ylim(-2, 102)
    shares.legend(fontsize=8)
    centre, axes = plane_frame(series["points"], series["normals"])
    xy = (series["points"] - centre) @ axes.T * 1e3
    status = series["status"][row]
    for k, name in enumerate(STATUS_NAMES):
        on = status == k
        where.scatter(xy[on, 0], xy[on, 1], s=12, color=COLOURS[k], label=name)
    where.set_aspect("equal")
    where.set_xlabel("[mm]")
    where.set_title(f"t = {t[row] * 1e3:.4g} ms", fontsize=9)
    where.legend(fontsize=8, loc="best")
    _suptitle(fig, f"{_title(stored)}: friction on pair '{series['pair']}'")
    fig.savefig(path, dpi=110)
    return row
