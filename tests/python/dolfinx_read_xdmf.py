# kdmesh — reads an XDMF file with dolfinx as a FEniCSx user would, and prints what it found as
# JSON (run in its own process by test_xdmf_dolfinx.py, so that MPI never starts in pytest's).
# SPDX-License-Identifier: AGPL-3.0-or-later
import json
import sys

import numpy as np
import ufl
from dolfinx import fem, io, mesh as dmesh
from mpi4py import MPI

with io.XDMFFile(MPI.COMM_WORLD, sys.argv[1], "r") as f:
    m = f.read_mesh(name="mesh")
    cells = f.read_meshtags(m, name="cell_tags")
    m.topology.create_connectivity(2, 3)
    facets = f.read_meshtags(m, name="facet_tags")
exterior = dmesh.exterior_facet_indices(m.topology)
values, counts = np.unique(facets.values, return_counts=True)
print(json.dumps({
    "cells": int(m.topology.index_map(3).size_global),
    "volume": float(fem.assemble_scalar(fem.form(fem.Constant(m, 1.0) * ufl.dx))),
    "cell_tag_count": int(cells.indices.size),
    "cell_tag_values": sorted(int(v) for v in np.unique(cells.values)),
    "facet_tag_count": int(facets.indices.size),
    "facets_are_exterior": bool(np.array_equal(np.sort(facets.indices), np.sort(exterior))),
    "exterior_facets": int(exterior.size),
    "facet_tag_counts": {str(int(v)): int(c) for v, c in zip(values, counts)},
}))
