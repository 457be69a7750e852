# kdmesh — sourced by the benchmarks that run Gmsh: gmsh_hxt_geo SURFACE H prints the .geo
# that meshes the closed triangulated SURFACE at the uniform size H the way a Gmsh user
# would: ClassifySurfaces (40 deg), CreateGeometry, one volume, HXT (Mesh.Algorithm3D 10)
# with the default optimiser, two threads.
# SPDX-License-Identifier: AGPL-3.0-or-later
gmsh_hxt_geo() {
  cat <<GEO
// kdmesh benchmark: Gmsh HXT from the part's triangles
Merge "$1";
ClassifySurfaces{40*Pi/180, 1, 1, Pi};
CreateGeometry;
Surface Loop(1) = Surface{:};
Volume(1) = {1};
Mesh.Algorithm3D = 10;
Mesh.MeshSizeMin = $2;
Mesh.MeshSizeMax = $2;
General.NumThreads = 2;
GEO
}
