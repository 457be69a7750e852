# kdmesh — the XDMF output read by its real client, FEniCSx (dolfinx 0.5, Debian's
# python3-dolfinx): the mesh, the cell tags (regions) and the facet tags (boundary groups).
# Skipped when dolfinx is not importable, unless KDMESH_REQUIRE_CLIENTS=1 (CI), where it fails.
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
from boxes import two_boxes, volume

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.environ.get("KDMESH_SOURCE_DIR", os.path.join(HERE, "..", ".."))
EXE = os.environ.get("KDMESH_EXE", os.path.join(SOURCE, "build", "kdmesh"))


def need_dolfinx():
    if importlib.util.find_spec("dolfinx") is None:
        if os.environ.get("KDMESH_REQUIRE_CLIENTS") == "1":
            pytest.fail("dolfinx (python3-dolfinx) is required but missing")
        pytest.skip("dolfinx (python3-dolfinx) is not installed")


def read_with_dolfinx(path):
    """What dolfinx finds in the XDMF file, read in a process of its own (MPI and PETSc stay out
    of pytest's; no sanitizer runtime preloaded: the reader loads nothing of ours)."""
    env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", "ASAN_OPTIONS")}
    run = subprocess.run([sys.executable, os.path.join(HERE, "dolfinx_read_xdmf.py"), str(path)],
                         capture_output=True, text=True, env=env, timeout=600)
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout.strip().splitlines()[-1])


def group_tags(xdmf_text):
    """name -> facet tag, from the facet grid's <Information Name="group" Value="tag name"/>."""
    return {name: int(tag) for tag, name in re.findall(r'<Information Name="group" Value="(\d+) ([^"]+)"/>', xdmf_text)}


def test_dolfinx_reads_mesh_cell_tags_and_facet_tags(tmp_path):
    need_dolfinx()
    m = kdmesh.mesh(two_boxes(), size=0.3, groups=[{"name": "load", "point": [0.5, 0.5, 1.0]}])
    path = tmp_path / "boxes.xdmf"
    kdmesh.write_xdmf(m, path)
    assert (tmp_path / "boxes.h5").is_file()
    got = read_with_dolfinx(path)

    assert got["cells"] == len(m.tets) == m.stats["counts"]["tets"]
    v = volume(m.points, m.tets)
    assert v == pytest.approx(2.0, rel=1e-9)
    assert got["volume"] == pytest.approx(v, rel=1e-9)
    assert got["cell_tag_count"] == len(m.tets)
    assert got["cell_tag_values"] == sorted(set(int(r) for r in m.regions))
    assert len(got["cell_tag_values"]) == 2
    # every boundary face tagged, and only boundary faces
    assert got["facet_tag_count"] == len(m.boundary_faces) == m.stats["counts"]["boundary_faces"]
    assert got["facets_are_exterior"] and got["exterior_facets"] == len(m.boundary_faces)
    # the named group's faces carry its tag; the rest 0 (in no surface group)
    tags = group_tags(path.read_text())
    load = tags["load"]
    dim, faces = m.groups["load"]
    assert dim == 2 and len(faces) > 0
    assert got["facet_tag_counts"] == {"0": len(m.boundary_faces) - len(faces), str(load): len(faces)}


def test_cli_and_python_write_the_same_xdmf(tmp_path):
    """kdmesh mesh --xdmf (through the job runner) writes what kdmesh.write_xdmf writes, byte for byte,
    and lists both files among the summary's outputs; dolfinx reads the quadratic mesh too."""
    need_dolfinx()
    (tmp_path / "cli").mkdir()
    (tmp_path / "py").mkdir()
    kdmesh.write_surface(tmp_path / "boxes.stl", *two_boxes())
    cli = tmp_path / "cli" / "boxes.xdmf"
    summary = tmp_path / "cli" / "boxes.json"
    subprocess.run([EXE, "mesh", str(tmp_path / "boxes.stl"), "--size", "0.3", "--element-order", "2", "-q",
                    "--xdmf", str(cli), "--summary", str(summary)], check=True)
    outputs = json.loads(summary.read_text())["outputs"]
    assert outputs["xdmf"] == str(cli) and outputs["xdmf_h5"] == str(tmp_path / "cli" / "boxes.h5")
    m = kdmesh.mesh(str(tmp_path / "boxes.stl"), size=0.3, element_order=2)
    py = tmp_path / "py" / "boxes.xdmf"
    kdmesh.write_xdmf(m, py)
    assert cli.read_bytes() == py.read_bytes()
    assert (tmp_path / "cli" / "boxes.h5").read_bytes() == (tmp_path / "py" / "boxes.h5").read_bytes()
    got = read_with_dolfinx(cli)
    assert got["cells"] == len(m.tets)
    assert got["facet_tag_count"] == len(m.boundary_faces)
    assert got["volume"] == pytest.approx(2.0, rel=1e-9)  # planar boxes: straight tet10s
