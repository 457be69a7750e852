# kdmesh — the Exodus II output read by its real clients: VTK's vtkExodusIIReader (ParaView's
# reader; Debian's python3-vtk9) and meshio (through netCDF4, python3-netcdf4): the tets, the
# element blocks per region, the side sets and node sets, and the volume.
# Each test is skipped when its reader is not importable, unless KDMESH_REQUIRE_CLIENTS=1 (CI),
# where it fails.
# SPDX-License-Identifier: AGPL-3.0-or-later
import importlib.util
import os

import numpy as np
import pytest

import kdmesh
from boxes import two_boxes, volume


def need(module, package):
    if importlib.util.find_spec(module) is None:
        if os.environ.get("KDMESH_REQUIRE_CLIENTS") == "1":
            pytest.fail(f"{module} ({package}) is required but missing")
        pytest.skip(f"{module} ({package}) is not installed")


GROUPS = [{"name": "load", "point": [0.5, 0.5, 1.0]},          # the first box's top (dim 2)
          {"name": "far_end", "point": [3.0, 0.5, 0.5]}]       # the second box's x = 3 side


@pytest.fixture(scope="module", params=[1, 2], ids=["tet4", "tet10"])
def written(request, tmp_path_factory):
    m = kdmesh.mesh(two_boxes(), size=0.3, groups=GROUPS, element_order=request.param)
    path = tmp_path_factory.mktemp("exodus") / "boxes.exo"
    kdmesh.write_exodus(m, path)
    return m, path, request.param


def region_counts(m):
    regions, counts = np.unique(np.asarray(m.regions), return_counts=True)
    return [int(c) for c in counts], [int(r) for r in regions]


def test_meshio_reads_blocks_node_sets_and_volume(written):
    need("meshio", "python3-meshio")
    need("netCDF4", "python3-netcdf4")
    import meshio
    m, path, order = written
    got = meshio.read(str(path))
    counts, _ = region_counts(m)
    assert [len(b.data) for b in got.cells] == counts          # one block per region, in region order
    assert sum(len(b.data) for b in got.cells) == len(m.tets) == m.stats["counts"]["tets"]
    assert {b.data.shape[1] for b in got.cells} == {4 if order == 1 else 10}
    tets = np.vstack([b.data[:, :4] for b in got.cells])
    assert volume(got.points, tets) == pytest.approx(2.0, rel=1e-9)
    if order == 1:  # (m.points are the corner nodes; order 2 adds the mid-edge nodes)
        assert len(got.points) == len(m.points)
    # node sets: one per group, named
    for name in ("load", "far_end"):
        nodes = got.point_sets[name]
        assert len(nodes) > 0
    assert np.allclose(got.points[got.point_sets["load"], 2], 1.0)
    assert np.allclose(got.points[got.point_sets["far_end"], 0], 3.0)


def leaves(output):
    """(name, dataset) of every non-empty leaf of the reader's multiblock output."""
    import vtk
    it = output.NewIterator()
    it.InitTraversal()
    out = []
    while not it.IsDoneWithTraversal():
        name = it.GetCurrentMetaData().Get(vtk.vtkCompositeDataSet.NAME())
        out.append((name, it.GetCurrentDataObject()))
        it.GoToNextItem()
    return out


def vtk_read(path, kind):
    """Reads only the element blocks, or only the side sets, or only the node sets."""
    import vtk
    r = vtk.vtkExodusIIReader()
    r.SetFileName(str(path))
    r.UpdateInformation()
    for t in (r.ELEM_BLOCK, r.SIDE_SET, r.NODE_SET):
        for i in range(r.GetNumberOfObjects(t)):
            r.SetObjectStatus(t, i, 1 if t == kind else 0)
    r.Update()
    names = [r.GetObjectName(kind, i) for i in range(r.GetNumberOfObjects(kind))]
    return names, leaves(r.GetOutput())


def points_of(ds):
    from vtk.util.numpy_support import vtk_to_numpy
    return vtk_to_numpy(ds.GetPoints().GetData())


def cells_of(ds):
    """Cell types and connectivity rows of an unstructured grid of one cell type."""
    from vtk.util.numpy_support import vtk_to_numpy
    types = vtk_to_numpy(ds.GetCellTypesArray())
    conn = vtk_to_numpy(ds.GetCells().GetConnectivityArray())
    return types, conn.reshape(ds.GetNumberOfCells(), -1)


def test_vtk_exodus_reader_reads_blocks_side_sets_and_node_sets(written):
    need("vtk", "python3-vtk9")
    m, path, order = written
    counts, regions = region_counts(m)

    names, blocks = vtk_read(path, 0 + 1)  # vtkExodusIIReader.ELEM_BLOCK == 1
    assert len(blocks) == len(counts) == 2
    assert [ds.GetNumberOfCells() for _, ds in blocks] == counts
    # named after the volume group of exactly that region (kdmesh's body_<i>)
    regions_of = np.asarray(m.regions)
    body = {int(regions_of[ids[0]]): name for name, (dim, ids) in m.groups.items()
            if dim == 3 and len(set(regions_of[ids].tolist())) == 1}
    assert names == [body[r] for r in regions]
    total = 0.0
    for _, ds in blocks:
        types, conn = cells_of(ds)
        assert set(types) == {10 if order == 1 else 24}   # VTK_TETRA / VTK_QUADRATIC_TETRA
        p = points_of(ds)
        total += volume(p, conn[:, :4])
        if order == 2:
            # Exodus TETRA10 read as VTK's quadratic tet: mid-edge node k between VTK's edge ends
            for k, (a, b) in enumerate([(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]):
                assert np.allclose(p[conn[:, 4 + k]], (p[conn[:, a]] + p[conn[:, b]]) / 2, atol=1e-12)
    assert total == pytest.approx(2.0, rel=1e-9)

    # side sets: the group's faces, each on its plane, covering its unit square
    names, sides = vtk_read(path, 3)  # SIDE_SET
    assert names == ["load", "far_end"]
    for (name, ds), axis, value in zip(sides, (2, 0), (1.0, 3.0)):
        dim, faces = m.groups[name]
        assert dim == 2 and ds.GetNumberOfCells() == len(faces)
        p = points_of(ds)
        _, conn = cells_of(ds)
        assert np.allclose(p[conn[:, :3].ravel(), axis], value)
        a = p[conn[:, 0]]
        area = np.linalg.norm(np.cross(p[conn[:, 1]] - a, p[conn[:, 2]] - a), axis=1).sum() / 2
        assert area == pytest.approx(1.0, rel=1e-9)

    names, nsets = vtk_read(path, 2)  # NODE_SET
    assert set(["load", "far_end"]) <= set(names)
    by_name = dict(zip(names, (ds for _, ds in nsets)))
    assert np.allclose(points_of(by_name["load"])[:, 2], 1.0)
    assert np.allclose(points_of(by_name["far_end"])[:, 0], 3.0)
