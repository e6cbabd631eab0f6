"""A part's mesh file as its case names it (parts.NAME.mesh.path and body): read, the body it
names taken, its errors named by the case's keys. Without Numba: a case whose reduction's
method is "auto" counts its files' cells at load (case.auto)."""
from ..errors import CaseError
from .body import take_body
from .fileerror import MeshFileError
from .meshfile import read_mesh
from .selections import find_set, offered


def read_part_file(case, name):
    """The Mesh of part `name`'s file, its body alone where the case names one, in the
    file's own frame and units."""
    key = f"parts.{name}.mesh"
    params = case.parts[name].mesh.params
    path = case.directory / params["path"]
    try:
        mesh = read_mesh(path)
    except MeshFileError as exc:
        raise CaseError(case.path, f"{key}.path", f"{exc.path}: {exc.message}") from None
    except ValueError as exc:
        raise CaseError(case.path, key, str(exc)) from None
    body = params["body"]
    if not body:
        return mesh
    found = find_set(mesh.cell_sets, body)
    if found is None:
        raise CaseError(case.path, f"{key}.body", f"{path} has no cell set '{body}' (cell "
                        f"sets, with a deck's instances: "
                        f"{', '.join(offered(mesh.cell_sets)) or 'none'})")
    return take_body(mesh, found)
