# kdmesh — an assembly of two touching bodies read and solved by real clients (issue 21):
# FEniCSx (dolfinx) solves steady heat conduction through the two layers from the XDMF file's
# cell and facet tags; VTK's Exodus reader and meshio read the Exodus file's blocks, side sets
# and node sets. Skipped without the client unless KDMESH_REQUIRE_CLIENTS=1 (CI).
# SPDX-License-Identifier: AGPL-3.0-or-later
import importlib.util
import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest

import kdmesh
from test_bodies import box_stl

HERE = os.path.dirname(os.path.abspath(__file__))


def need(module, package):
    if importlib.util.find_spec(module) is None:
        if os.environ.get("KDMESH_REQUIRE_CLIENTS") == "1":
            pytest.fail(f"{module} ({package}) is required but missing")
        pytest.skip(f"{module} ({package}) is not installed")


def layers(tmp_path, size):
    """Two touching boxes along x, [0, 1] and [1, 2] (the unit square x = 1 between them), with
    the end faces as groups: one mesh, each box its region."""
    a = box_stl(tmp_path / "first.stl", [0, 0, 0], [1, 1, 1])
    b = box_stl(tmp_path / "second.stl", [1, 0, 0], [2, 1, 1])
    return kdmesh.mesh(None, size=size, bodies=[{"name": "first", "input": a}, {"name": "second", "input": b}],
                       groups=[{"name": "cool", "point": [0, 0.5, 0.5]}, {"name": "warm", "point": [2, 0.5, 0.5]}])


def test_interface_faces_are_shared_by_one_tet_of_each_region(tmp_path):
    m = layers(tmp_path, 0.2)
    dim, faces = m.groups["first-second"]
    assert dim == 2
    tri = np.sort(m.fe_faces[faces][:, :3], axis=1)
    assert np.allclose(m.points[tri][:, :, 0], 1.0, atol=1e-12)  # on the plane x = 1
    # each interface face is a face of exactly one tet of each region
    tet_faces = {}
    for t, tet in enumerate(m.tets):
        for skip in range(4):
            key = tuple(sorted(np.delete(tet, skip)))
            tet_faces.setdefault(key, []).append(int(m.regions[t]))
    for f in map(tuple, tri):
        assert sorted(tet_faces[f]) == [0, 1]
    p = m.points[tri]
    area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum() / 2
    assert area == pytest.approx(1.0, rel=1e-12)
    for body in m.stats["bodies"]:
        assert body["min_dihedral"] >= 12 and body["max_dihedral"] <= 165


def test_dolfinx_solves_heat_conduction_through_the_two_layers(tmp_path):
    """T = 0 at x = 0, T = 1 at x = 2, conductivities 1 and 3: the exact temperature is linear in
    each layer, 0.75 at the interface, and the flux 0.75 through every section. Linear elements
    hold it exactly when every tet lies in one layer (cell tags right, interface conforming)."""
    need("dolfinx", "python3-dolfinx")
    m = layers(tmp_path, 0.25)
    path = tmp_path / "layers.xdmf"
    kdmesh.write_xdmf(m, path)
    tags = {name: int(tag) for tag, name in
            re.findall(r'<Information Name="group" Value="(\d+) ([^"]+)"/>', path.read_text())}
    env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", "ASAN_OPTIONS")}
    run = subprocess.run([sys.executable, os.path.join(HERE, "dolfinx_bimaterial.py"), str(path),
                          str(tags["cool"]), str(tags["warm"]), "1", "3"],
                         capture_output=True, text=True, env=env, timeout=600)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout.strip().splitlines()[-1])
    assert got["cells"] == len(m.tets) and got["regions"] == [0, 1]
    assert got["cool_facets"] > 0 and got["warm_facets"] > 0
    x, T = np.array(got["x"]), np.array(got["T"])
    exact = np.where(x <= 1, 0.75 * x, 0.75 + 0.25 * (x - 1))
    err = np.abs(T - exact).max()
    print(f"dolfinx: {got['cells']} cells, max |T - exact| {err:.3g}, flux {got['flux']:.6f} (exact 0.75)")
    assert err <= 0.01 * 0.75
    assert got["flux"] == pytest.approx(0.75, rel=0.01)  # heat flows to the cool face and leaves there


def test_exodus_readers_find_the_blocks_side_sets_and_node_sets(tmp_path):
    """VTK's vtkExodusIIReader (ParaView's) and meshio read one element block per body, one side
    set per facet group (the exteriors, the interface, the user's groups) and the node sets,
    with kdmesh's counts."""
    need("vtk", "python3-vtk9")
    need("meshio", "python3-meshio")
    need("netCDF4", "python3-netcdf4")
    import meshio
    from test_exodus_clients import cells_of, points_of, vtk_read
    m = layers(tmp_path, 0.25)
    path = tmp_path / "layers.exo"
    kdmesh.write_exodus(m, path)
    counts = [int(np.count_nonzero(m.regions == r)) for r in (0, 1)]

    names, blocks = vtk_read(path, 1)  # ELEM_BLOCK
    assert names == ["first", "second"]
    assert [ds.GetNumberOfCells() for _, ds in blocks] == counts
    faces = {name: ids for name, (dim, ids) in m.groups.items() if dim == 2}
    names, sides = vtk_read(path, 3)  # SIDE_SET
    assert set(names) == set(faces) >= {"cool", "warm", "first-exterior", "second-exterior", "first-second"}
    by_name = dict(zip(names, (ds for _, ds in sides)))
    for name, ids in faces.items():
        assert by_name[name].GetNumberOfCells() == len(ids), name
    p = points_of(by_name["first-second"])
    _, conn = cells_of(by_name["first-second"])
    assert np.allclose(p[conn.ravel(), 0], 1.0)
    a = p[conn[:, 0]]
    assert np.linalg.norm(np.cross(p[conn[:, 1]] - a, p[conn[:, 2]] - a), axis=1).sum() / 2 == pytest.approx(1.0)
    names, nsets = vtk_read(path, 2)  # NODE_SET
    assert set(faces) <= set(names)

    got = meshio.read(str(path))
    assert [len(b.data) for b in got.cells] == counts
    assert set(faces) <= set(got.point_sets)
    assert np.allclose(got.points[got.point_sets["first-second"], 0], 1.0)
