"""Contact pressures stored in a history, ready to map: force, plane, pair checks and panels.

Numbers only, nothing is drawn: the total normal contact force of a pair at every row, the
best-fit plane (centre and in-plane axes) of the contact points seen from surface 1, the pair
to map (checked to have its pressures and point positions stored), a text naming the rule of a
pair, and the data of the pressure panels (one per history, at one time) drawn by
`history.pressure_figure`.
"""
import numpy as np

FORCE_CHUNK = 4096      # rows of pressure read at a time for the total force


def contact_force(stored, pair):
    """Total normal contact force sum_i w_i p_i [N] of a pair at every row."""
    w = stored.contact_geometry(pair)["weights"]
    force = np.zeros(stored.rows)
    with stored.open() as f:
        ds = f[f"contact/{pair}/pressure"]
        for start in range(0, stored.rows, FORCE_CHUNK):
            stop = min(start + FORCE_CHUNK, stored.rows)
            force[start:stop] = ds[start:stop] @ w
    return force


def plane_frame(points, normals):
    """Centre and in-plane axes of the best-fit plane of contact points, seen from surface 1.

    The plane is the SVD's (its normal the direction of least spread), its normal n oriented
    as the mean stored contact normal (surface 2 towards surface 1); with fewer than three
    points off a line, the plane normal to the mean stored normal. The first axis is the global
    axis most nearly in the plane, projected on it, so that the maps of different rules, runs
    and meshes are drawn the same way round.

    Parameters
    ----------
    points : (m, 3) array [m]
    normals : (m, 3) array
        Contact normals at the points.

    Returns
    -------
    centre : (3,) array [m]
    axes : (2, 3) array
        In-plane unit vectors e1, e2 with e1 x e2 = n.
    """
    centre = points.mean(axis=0)
    n_mean = normals.mean(axis=0)
    _, s, vt = np.linalg.svd(points - centre, full_matrices=True)
    if len(s) >= 2 and s[1] > 1e-9 * s[0]:
        n = vt[2] if vt[2] @ n_mean >= 0 else -vt[2]
    else:
        n = n_mean / np.linalg.norm(n_mean)
    # rounded: of two axes both in the plane up to round-off, x before y before z
    e1 = np.eye(3)[np.argmin(np.round(np.abs(n), 9))]
    e1 = e1 - (e1 @ n) * n
    e1 /= np.linalg.norm(e1)
    return centre, np.array([e1, np.cross(n, e1)])


def contact_pair(stored, pair):
    """The pair to map (default the first stored), checked to have its pressures and its
    points' positions, normals and weights."""
    stored_pairs = [name.split("/")[1] for name in stored.series
                    if name.startswith("contact/") and name.endswith("/pressure")]
    if not stored_pairs:
        raise stored.error("contact", "no contact pressures stored: run with "
                           "output.contact = true")
    pair = pair or stored_pairs[0]
    if pair not in stored_pairs:
        raise stored.error("--pair", f"no contact pair '{pair}' stored (pairs: "
                           f"{', '.join(stored_pairs)})")
    stored.contact_geometry(pair)
    return pair


def rule_text(description):
    """'fine rule', 'centre rule, regularized (eps = 1e-08)'... from a history's pairs entry."""
    text = f"{description.get('rule', '?')} rule"
    if description.get("regularized"):
        eps = description.get("eps")
        text += ", regularized" + (f" (eps = {eps:.2g})" if eps is not None else "")
    return text


def pressure_panels(histories, pair=None, time=None, labels=None):
    """The data of the pressure maps: one panel per history, at one time.

    Parameters
    ----------
    histories : list of stored.Stored
    pair : str, optional
        Contact pair (default the first of the first history).
    time : float, optional
        Time [s]: each panel shows its stored row nearest to it. Default: the time of the
        largest total contact force of the first history.
    labels : list of str, optional
        Panel names (default the file names).

    Returns
    -------
    list of dict
        Each with points (m, 3) [m], normals (m, 3), weights (m,) [m^2], pressure (m,) [Pa],
        time [s] and force [N] (the total) of the row shown, pair (its name), rule (a text
        from the history's `pairs`) and label.
    """
    pair = contact_pair(histories[0], pair)
    panels = []
    for k, stored in enumerate(histories):
        contact_pair(stored, pair)
        t = stored.time()
        force = contact_force(stored, pair)
        if k == 0 and time is None:
            time = float(t[np.argmax(force)])
        row = int(np.argmin(np.abs(t - time)))
        with stored.open() as f:
            pressure = f[f"contact/{pair}/pressure"][row]
        panels.append({**stored.contact_geometry(pair), "pressure": pressure,
                       "time": float(t[row]), "force": float(force[row]), "pair": pair,
                       "rule": rule_text(stored.pairs().get(pair, {})),
                       "label": labels[k] if labels else stored.path.stem})
    return panels
