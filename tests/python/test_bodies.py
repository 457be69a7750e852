# kdmesh — named bodies from Python (issue 21): kdmesh.mesh(None, bodies=[...]) meshes several
# solids, each its region in list order and its named volume group, through meshio and the
# Gmsh writer; touching bodies share a conforming interface, overlapping ones raise SurfaceError
# naming both and a point.
# SPDX-License-Identifier: AGPL-3.0-or-later
import numpy as np
import pytest

import kdmesh


def box_stl(path, lo, hi):
    """The box [lo, hi] as an ASCII STL with outward facets."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    v = np.array([[hi[0] if i & 1 else lo[0], hi[1] if i >> 1 & 1 else lo[1], hi[2] if i >> 2 & 1 else lo[2]]
                  for i in range(8)])
    f = np.array([0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                  2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5]).reshape(-1, 3)
    lines = ["solid box"]
    for t in f:
        n = np.cross(v[t[1]] - v[t[0]], v[t[2]] - v[t[0]])
        lines.append("facet normal %r %r %r" % tuple(n / np.linalg.norm(n)))
        lines.append("outer loop")
        lines += ["vertex %r %r %r" % tuple(v[i]) for i in t]
        lines += ["endloop", "endfacet"]
    lines.append("endsolid box")
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_bodies_are_named_regions_in_list_order(tmp_path):
    import meshio
    right = box_stl(tmp_path / "right.stl", [2, 0, 0], [3, 1, 1])
    left = box_stl(tmp_path / "left.stl", [0, 0, 0], [1, 1, 1])
    m = kdmesh.mesh(None, size=0.3, bodies=[{"name": "right", "input": right}, {"name": "left", "input": left}])
    centroids = m.points[m.tets].mean(axis=1)
    assert np.array_equal(m.regions, np.where(centroids[:, 0] > 1.5, 0, 1))
    for k, name in enumerate(["right", "left"]):
        dim, tets = m.groups[name]
        assert dim == 3 and np.array_equal(tets, np.flatnonzero(m.regions == k))
        body = m.stats["bodies"][k]
        assert body["name"] == name and body["region"] == k and body["input"].endswith(name + ".stl")
        assert body["mesh_volume"] == pytest.approx(1.0, rel=1e-9)
        assert body["tets"] == len(tets)
    assert "body_1" not in m.groups
    assert set(m.to_meshio().cell_sets) >= {"right", "left"}
    msh = tmp_path / "a.msh"
    kdmesh.write_msh(m, msh)
    back = meshio.read(msh)
    assert back.field_data["right"][1] == 3 and back.field_data["left"][1] == 3  # physical volumes


def test_touching_bodies_share_one_interface_and_overlapping_ones_raise(tmp_path):
    """Regression (issue 21): touching bodies raised SurfaceError; now they are meshed with one
    conforming interface, the group 'a-b', and only overlapping ones raise."""
    a = box_stl(tmp_path / "a.stl", [0, 0, 0], [1, 1, 1])
    b = box_stl(tmp_path / "b.stl", [1, 0, 0], [2, 1, 1])
    m = kdmesh.mesh(None, size=0.3, bodies=[{"name": "a", "input": a}, {"name": "b", "input": b}])
    centroids = m.points[m.tets].mean(axis=1)
    assert np.array_equal(m.regions, np.where(centroids[:, 0] > 1, 1, 0))
    dim, faces = m.groups["a-b"]
    assert dim == 2 and len(faces) > 0
    assert m.stats["mesh_check"]["interface_faces"] == len(faces)
    for name in ("a-exterior", "b-exterior"):
        assert m.groups[name][0] == 2 and len(m.groups[name][1]) > 0
    half = box_stl(tmp_path / "half.stl", [0.5, 0, 0], [1.5, 1, 1])
    with pytest.raises(kdmesh.SurfaceError) as e:
        kdmesh.mesh(None, size=0.3, bodies=[{"name": "a", "input": a}, {"name": "half", "input": half}])
    assert "'a' and 'half' overlap" in str(e.value)
    assert e.value.bodies == ["a", "half"] and e.value.exit_code == 4
    assert e.value.where.shape == (1, 3)
    with pytest.raises(kdmesh.UsageError):
        kdmesh.mesh(a, size=0.3, bodies=[{"name": "b", "input": b}])  # a surface and bodies
    with pytest.raises(kdmesh.UsageError):
        kdmesh.mesh(None, size=0.3)  # neither
