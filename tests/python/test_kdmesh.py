# kdmesh — the Python module (tools/python): numpy round trips, meshio, errors as exceptions,
# cancellation, zones and groups from Python, the same mesh as the CLI, the Delaunay entry.
# Run by ctest (python_tests) with PYTHONPATH=<build>/python, KDMESH_EXE and KDMESH_SOURCE_DIR.
# SPDX-License-Identifier: AGPL-3.0-or-later
import os
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

import kdmesh

SOURCE = os.environ.get("KDMESH_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
EXE = os.environ.get("KDMESH_EXE", os.path.join(SOURCE, "build", "kdmesh"))
BLOCK = os.path.join(SOURCE, "models", "block", "block.stl")


def box(a=1.0, b=1.0, c=1.0):
    v = np.array([[(i & 1) * a, (i >> 1 & 1) * b, (i >> 2 & 1) * c] for i in range(8)], dtype=float)
    f = np.array([0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                  2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5]).reshape(-1, 3)
    return v, f


def volume(points, tets):
    p = points[tets]
    return np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])).sum() / 6


def test_arrays_and_path_give_the_same_mesh_and_numpy_round_trips(tmp_path):
    v, f = kdmesh.read_surface(BLOCK)
    assert v.dtype == np.float64 and v.shape[1] == 3 and f.shape[1] == 3
    from_path = kdmesh.mesh(BLOCK, size=12.0)
    from_arrays = kdmesh.mesh((v, f), size=12.0)
    assert np.array_equal(from_path.points, from_arrays.points)
    assert np.array_equal(from_path.tets, from_arrays.tets)
    assert from_path.tets.shape[1] == 4 and from_path.points.shape[1] == 3
    assert volume(from_path.points, from_path.tets) == pytest.approx(100.0 ** 3, rel=1e-9)
    assert from_path.stats["status"] == "ok" and from_path.stats["mesh_check"]["pass"]
    assert from_path.stats["counts"]["tets"] == len(from_path.tets)
    # write_surface / read_surface keep every double
    bv, bf = box(0.1, 0.2, 0.3)
    out = tmp_path / "box.ply"
    kdmesh.write_surface(out, bv, bf)
    rv, rf = kdmesh.read_surface(out)
    assert np.array_equal(rv[rf], bv[bf])


def test_same_mesh_as_the_cli_for_the_same_job(tmp_path):
    cli = tmp_path / "cli.vtu"
    subprocess.run([EXE, "mesh", BLOCK, "--size", "12", "--gradation", "0.2", "-q", "-o", str(cli)], check=True)
    m = kdmesh.mesh(BLOCK, size=12.0, gradation=0.2)
    py = tmp_path / "py.vtu"
    kdmesh.write_vtu(m, py)
    assert cli.read_bytes() == py.read_bytes()


def test_to_meshio_with_groups_and_solver_formats(tmp_path):
    import meshio
    m = kdmesh.mesh(BLOCK, size=12.0, patch_groups=True,
                    groups=[{"name": "load", "point": [50, 50, 100]}])
    dim, faces = m.groups["load"]
    assert dim == 2 and len(faces) > 0
    assert np.allclose(m.points[m.fe_faces[faces]][..., 2], 100.0)  # the top face only
    assert m.groups["body_1"][0] == 3 and len(m.groups["body_1"][1]) == len(m.tets)
    mm = m.to_meshio()
    assert "load" in mm.cell_sets and len(mm.cell_sets["load"][1]) == len(faces)
    path = tmp_path / "block.vtu"
    mm.write(path)
    back = meshio.read(path)
    assert len(back.cells_dict["tetra"]) == len(m.tets)
    msh = tmp_path / "block.msh"
    kdmesh.write_msh(m, msh)
    assert len(meshio.read(msh).cells_dict["tetra"]) == len(m.tets)
    kdmesh.write_inp(m, tmp_path / "block.inp")
    assert "*ELEMENT" in (tmp_path / "block.inp").read_text().upper()
    plain = kdmesh.mesh(BLOCK, size=12.0)
    with pytest.raises(kdmesh.UsageError):
        kdmesh.write_msh(plain, tmp_path / "plain.msh")


def test_zones_from_python_refine_where_they_are():
    coarse = kdmesh.mesh(box(10, 10, 10), size=2.0)
    fine = kdmesh.mesh(box(10, 10, 10), size=2.0, zones=[{"type": "point", "at": [0, 0, 0], "size": 0.25}])
    assert len(fine.points) > len(coarse.points)
    near = np.linalg.norm(fine.points, axis=1) < 0.5
    assert near.sum() > 4 and fine.target_size[near].max() < 0.5
    assert fine.stats["options"]["zones"] == 1


def test_errors_become_exceptions_with_their_data(tmp_path):
    v, f = box()
    with pytest.raises(kdmesh.SurfaceError) as e:  # a facet missing: open surface
        kdmesh.mesh((v, f[:-1]), size=0.3)
    assert e.value.exit_code == 4 and isinstance(e.value, kdmesh.GeometryError)
    assert e.value.summary["status"] == "failed"
    with pytest.raises(kdmesh.UsageError) as e:  # unknown key, with the closest valid one
        kdmesh.mesh((v, f), size=0.3, gradaton=0.2)
    assert "gradation" in str(e.value) and e.value.exit_code == 2
    with pytest.raises(kdmesh.InputError) as e:
        kdmesh.mesh(str(tmp_path / "missing.stl"), size=0.3)
    assert e.value.file.endswith("missing.stl")
    bad = tmp_path / "bad.stl"
    bad.write_text("solid x\n  facet normal 0 0 1\n  oops\n")
    with pytest.raises(kdmesh.InputError) as e:
        kdmesh.read_surface(bad)
    assert e.value.line > 0 and e.value.exit_code == 3
    with pytest.raises(kdmesh.ResourceError) as e:
        kdmesh.mesh((v, f), size=0.01, max_memory="1M")
    assert e.value.summary["estimate"]["peak_bytes"] > 1e6
    with pytest.raises(kdmesh.UsageError):
        kdmesh.mesh((v, np.array([[0, 1, 9]])), size=0.3)  # vertex id out of range


def test_cancellation_stops_the_job_and_leaves_no_state():
    stages = []

    def progress(stage, fraction):
        assert 0.0 <= fraction <= 1.0
        stages.append(stage)

    plain = kdmesh.mesh(box(), size=0.08)
    with pytest.raises(kdmesh.CancelledError) as e:
        kdmesh.mesh(box(), size=0.08, progress=progress, cancel=lambda: "delaunay" in stages)
    assert "delaunay" in stages and e.value.exit_code == 130
    assert "tets" not in e.value.summary.get("counts", {})  # stopped inside the volume mesh
    again = kdmesh.mesh(box(), size=0.08)
    assert np.array_equal(again.tets, plain.tets)


def test_ctrl_c_interrupts_promptly_and_the_gil_is_released():
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.01)

    t = threading.Thread(target=ticker)
    t.start()
    try:
        start = time.monotonic()
        kdmesh.mesh(box(), size=0.03)  # 0.2-0.4 s here
        end = time.monotonic()
    finally:
        stop.set()
        t.join()
    # The other thread ran while C++ meshed: it ticks every 10 ms, and could not once the call
    # held the GIL. (Counted within the call: a fixed count assumed a slower mesher.)
    during = [x for x in ticks if start < x < end]
    assert end - start > 0.1
    assert len(during) >= 0.3 * (end - start) / 0.01

    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        kdmesh.mesh(box(), size=0.02)  # several seconds of work
    assert time.monotonic() - start < 5.0
    timer.join()


def test_delaunay_entry_matches_scipy_and_ignores_the_order():
    from scipy.spatial import Delaunay
    rng = np.random.default_rng(7)
    pts = rng.random((2000, 3))
    tets, stats = kdmesh.delaunay(pts, order="kd-bfs")
    assert tets.shape[1] == 4 and stats["inserted"] == 2000
    assert len(tets) == len(Delaunay(pts).simplices)
    for order in ("hilbert", "random", "input"):
        other, _ = kdmesh.delaunay(pts, order=order)
        assert {tuple(sorted(t)) for t in other} == {tuple(sorted(t)) for t in tets}
    assert (volume(pts, tets.astype(np.int64)) > 0)
    with pytest.raises(kdmesh.UsageError):
        kdmesh.delaunay(pts, order="nope")
