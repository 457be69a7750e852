# kdmesh — steady heat conduction through two layers, solved by dolfinx on kdmesh's XDMF of two
# touching bodies (run in its own process by test_assembly.py; prints what it found as JSON).
# argv: the XDMF file, the facet tag of the cool face (T = 0), of the warm face (T = 1), then
# the conductivity of region 0 and of region 1.
# SPDX-License-Identifier: AGPL-3.0-or-later
import json
import sys

import numpy as np
import ufl
from dolfinx import fem, io
from dolfinx.fem.petsc import LinearProblem
from mpi4py import MPI
from petsc4py import PETSc

path, cool, warm, k0, k1 = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
with io.XDMFFile(MPI.COMM_WORLD, path, "r") as f:
    m = f.read_mesh(name="mesh")
    cells = f.read_meshtags(m, name="cell_tags")
    m.topology.create_connectivity(2, 3)
    facets = f.read_meshtags(m, name="facet_tags")
# The conductivity per cell, from the regions (cell tags).
Q = fem.FunctionSpace(m, ("DG", 0))
k = fem.Function(Q)
k.x.array[cells.indices] = np.where(cells.values == 0, k0, k1)
V = fem.FunctionSpace(m, ("CG", 1))
bcs = [fem.dirichletbc(PETSc.ScalarType(value), fem.locate_dofs_topological(V, 2, facets.indices[facets.values == tag]), V)
       for tag, value in ((cool, 0.0), (warm, 1.0))]
T, v = ufl.TrialFunction(V), ufl.TestFunction(V)
zero = fem.Constant(m, PETSc.ScalarType(0.0))
problem = LinearProblem(k * ufl.inner(ufl.grad(T), ufl.grad(v)) * ufl.dx, zero * v * ufl.dx, bcs=bcs,
                        petsc_options={"ksp_type": "preonly", "pc_type": "lu"})
Th = problem.solve()
x = V.tabulate_dof_coordinates()
# The heat flux out through the cool face: -k grad T . n integrated over it.
ds = ufl.Measure("ds", domain=m, subdomain_data=facets)
n = ufl.FacetNormal(m)
flux = fem.assemble_scalar(fem.form(-k * ufl.dot(ufl.grad(Th), n) * ds(cool)))
print(json.dumps({
    "cells": int(m.topology.index_map(3).size_global),
    "regions": sorted(int(r) for r in np.unique(cells.values)),
    "x": x[:, 0].tolist(),
    "T": Th.x.array.tolist(),
    "cool_facets": int(np.count_nonzero(facets.values == cool)),
    "warm_facets": int(np.count_nonzero(facets.values == warm)),
    "flux": float(flux),
}))
