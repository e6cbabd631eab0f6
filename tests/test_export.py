"""`transient export`: contact points and displacement field as time series ParaView opens."""
from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest
import pyvista as pv
import vtk

from transient.case.loading import load
from transient.cli import main
from transient.io.export import exported_rows
from transient.io.attributes import CASE_TEXT
from transient.model.model import build_model
from transient.integration import run

CASE = Path(__file__).resolve().parent.parent / "cases" / "bar_impact.toml"
FULL = ["output.field=true", "solver.t_end=3e-5"]    # 308 rows (dt 9.77e-8 s), contact from 10 us
# 40 elements: 492 free dofs, so the modes to 1 MHz come from a dense eigensolver in no time
REDUCED = FULL + ["parts.bar.mesh.divisions=[40,1,1]", "solver.reduction.enabled=true",
                  "solver.reduction.fmax=1e6", "solver.scheme=exponential", "solver.dt=2e-7"]


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    path = tmp_path_factory.mktemp("export") / "bar.h5"
    run(load(CASE, FULL), path)
    return path


def _stored(path, name):
    with h5py.File(path, "r") as f:
        return f[name][()]


def _printed(capsys):
    return [Path(p) for p in capsys.readouterr().out.split()]


@pytest.mark.slow
def test_xdmf_of_a_full_model(full, tmp_path, capsys):
    out = tmp_path / "xdmf"
    assert main(["export", str(full), "--out", str(out)]) == 0
    assert _printed(capsys) == [out / "contact_wall.xdmf", out / "field.xdmf"]
    time, q = _stored(full, "time"), _stored(full, "field/q")
    tip = _stored(full, "sensors/tip")
    model = build_model(load(CASE, FULL))
    u = np.zeros(model.ndof)
    u[model.free] = q[-1]
    with meshio.xdmf.TimeSeriesReader(out / "field.xdmf") as reader:
        points, cells = reader.read_points_cells()
        assert reader.num_steps == len(time) == 308
        assert np.allclose(points, model.points) and cells[0].type == "hexahedron"
        t, data, _ = reader.read_data(reader.num_steps - 1)
    assert t == time[-1]
    assert np.array_equal(data["displacement"], u.reshape(-1, 3))
    # the bar's end moved along x by what the tip sensor saw (10 um to the wall, then held)
    end = np.isclose(points[:, 0], 0.1)
    assert np.allclose(data["displacement"][end, 0], tip[-1], rtol=1e-6)
    assert tip[-1] == pytest.approx(1e-5, rel=0.05)
    with meshio.xdmf.TimeSeriesReader(out / "contact_wall.xdmf") as reader:
        points, _ = reader.read_points_cells()
        t, data, _ = reader.read_data(reader.num_steps - 1)
    assert np.array_equal(points, _stored(full, "geometry/contact/wall/points"))
    assert np.array_equal(data["pressure"], _stored(full, "contact/wall/pressure")[-1])
    assert np.array_equal(data["gap"], _stored(full, "contact/wall/gap")[-1])
    # VTK's XDMF reader (ParaView's "Xdmf Reader") sees the time steps and the field
    reader = pv.XdmfReader(str(out / "field.xdmf"))
    assert len(reader.time_values) == 308
    reader.set_active_time_value(reader.time_values[-1])
    grid = reader.read()["TimeSeries_meshio"]
    assert np.allclose(grid.point_data["displacement"], u.reshape(-1, 3))


@pytest.mark.slow
def test_vtu_and_pvd_of_a_reduced_model(tmp_path, capsys):
    path = tmp_path / "reduced.h5"
    case = load(CASE, REDUCED)
    run(case, path)
    out = tmp_path / "vtu"
    assert main(["export", str(path), "--out", str(out), "--format", "vtu",
                 "--every", "40"]) == 0
    assert _printed(capsys) == [out / "contact_wall.pvd", out / "field.pvd"]
    time = _stored(path, "time")
    rows = exported_rows(len(time), 40)
    assert list(rows) == [0, 40, 80, 120, 150]
    reader = pv.PVDReader(str(out / "field.pvd"))
    assert np.allclose(reader.time_values, time[rows], rtol=1e-12)
    reader.set_active_time_value(reader.time_values[-1])
    u = reader.read()[0].point_data["displacement"].ravel()
    # the sensors the kernel observed during the run, from the exported field
    model = build_model(case)
    stored = [_stored(path, f"sensors/{name}")[-1] for name in model.sensor_names]
    assert np.allclose(model.sensors @ u, stored, rtol=1e-9, atol=1e-15)
    cloud = pv.PVDReader(str(out / "contact_wall.pvd"))
    cloud.set_active_time_value(cloud.time_values[-1])
    points = cloud.read()[0]
    assert points.n_points == 12
    assert np.allclose(points.point_data["pressure"], _stored(path, "contact/wall/pressure")[-1])
    # the case text of another model (fuzz seed 1, #1369): the stored basis misses its mesh
    with h5py.File(path, "r+") as f:
        f.attrs[CASE_TEXT] = (CASE.parent / "two_bars.toml").read_text()
        f.attrs["overrides"] = '["output.field=true"]'
    assert main(["export", str(path), "--out", str(tmp_path / "other")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{path}: geometry/field/basis: " in err


@pytest.mark.parametrize("every", [2 ** 63, 10 ** 30])
def test_a_step_past_the_last_row_exports_the_first_and_the_last(every):
    rows = exported_rows(191, every)
    assert rows.tolist() == [0, 190] and rows.dtype.kind == "i"     # indices, not floats


def test_a_case_changed_since_the_run_is_caught(full, tmp_path, capsys):
    path = tmp_path / "moved_sensor.h5"
    path.write_bytes(full.read_bytes())
    with h5py.File(path, "r+") as f:
        text = f.attrs[CASE_TEXT]
        assert "point = [0.1, 0.005, 0.005]" in text
        f.attrs[CASE_TEXT] = text.replace("point = [0.1, 0.005, 0.005]",
                                          "point = [0.05, 0.005, 0.005]")
    assert main(["export", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "misses the stored sensors" in err and str(path) in err


def test_nothing_to_export_is_one_line_error(tmp_path, capsys):
    path = tmp_path / "bare.h5"
    run(load(CASE, ["solver.t_end=2e-6", "output.contact=false"]), path)
    assert main(["export", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(path) in err
    assert "output.field = true" in err and "output.contact = true" in err
    assert main(["export", str(tmp_path / "missing.h5")]) == 2
    assert "file not found" in capsys.readouterr().err


@pytest.mark.parametrize("fmt, element", [("vtu", "wedge6"), ("xdmf", "wedge6"),
                                          ("vtu", "wedge15")])
def test_wedges_export_as_cells_vtk_holds_valid(tmp_path, capsys, fmt, element):
    """meshio's VTU writer turns linear wedges over (after VTK's old documentation); VTK's
    cell validator and its signed volumes are the judges of what ParaView will show."""
    path = tmp_path / "wedges.h5"
    run(load(CASE, ["output.field=true", "solver.t_end=2e-6", "parts.bar.mesh.divisions=[10,1,1]",
                    f'parts.bar.mesh.element="{element}"']), path)
    out = tmp_path / fmt
    assert main(["export", str(path), "--out", str(out), "--format", fmt]) == 0
    capsys.readouterr()
    if fmt == "vtu":
        reader = pv.PVDReader(str(out / "field.pvd"))
        reader.set_active_time_value(reader.time_values[-1])
        grid = reader.read()[0]
    else:
        grid = pv.XdmfReader(str(out / "field.xdmf")).read()["TimeSeries_meshio"]
    assert grid.n_cells == 20
    validator = vtk.vtkCellValidator()
    validator.SetInputData(grid)
    validator.Update()
    assert set(pv.wrap(validator.GetOutput())["ValidityState"]) == {0}
    assert grid.compute_cell_sizes()["Volume"].min() > 0
