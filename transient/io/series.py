"""The series of a history: their names and row shapes (the layout), and a chunk's rows under
those names. What is stored follows the case's output spec."""
from ..kernels.codes import ENERGY_TERMS


def layout(system, output):
    """Series name -> shape of one row."""
    shapes = {"time": ()}
    shapes.update({f"sensors/{name}": () for name in system.sensor_names})
    if system.n_field:
        shapes["field/q"] = (system.n_field,)
    if output.contact:
        for name, s in system.contacts.slices.items():
            shapes[f"contact/{name}/gap"] = (s.stop - s.start,)
            shapes[f"contact/{name}/pressure"] = (s.stop - s.start,)
            if system.contacts.friction is not None:
                shapes[f"contact/{name}/slip"] = (2, s.stop - s.start)
    if output.energy:
        shapes.update({f"energy/{term}": () for term in ENERGY_TERMS})
    return shapes


def series(system, output, rows):
    """Series name -> the rows (dynamics.state.Rows) of that series."""
    out = {"time": rows.time}
    names = system.sensor_names
    out.update({f"sensors/{name}": rows.sensors[:, k] for k, name in enumerate(names)})
    if system.n_field:
        out["field/q"] = rows.sensors[:, len(names):]
    if output.contact:
        for name, s in system.contacts.slices.items():
            out[f"contact/{name}/gap"] = rows.gap[:, s]
            out[f"contact/{name}/pressure"] = rows.pressure[:, s]
            if system.contacts.friction is not None:
                out[f"contact/{name}/slip"] = rows.slip[:, :, s]
    if output.energy:
        out.update({f"energy/{term}": rows.energy[:, k] for k, term in enumerate(ENERGY_TERMS)})
    return out
