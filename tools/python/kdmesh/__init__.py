# kdmesh — tetrahedral meshes of closed surfaces, from Python.
# SPDX-License-Identifier: AGPL-3.0-or-later
"""kdmesh: tetrahedral meshes of closed surfaces for finite elements.

    import kdmesh
    m = kdmesh.mesh("part.stl", size=2.0)                 # or mesh((vertices, triangles), ...)
    m.points, m.tets, m.regions, m.boundary_faces, m.groups, m.stats
    m.to_meshio().write("part.vtu")

The keyword options are the keys of a batch file's job (README, "Batch files"), with the same
meaning and checks: size, min_size, gradation, sharp_angle, zones, curvature_angle,
chordal_deviation, auto_creases, thickness_layers, tolerance, max_refinements, order, seed,
check, max_memory, repair, groups, patch_groups, improve, element_order, msh_version, output,
timeout, scale, name. Errors raise the subclasses of kdmesh.Error, carrying the data the C++
error carries (file and line, facet ids, places, the job's summary).
"""
import functools
import json as _json

import numpy as _np

from . import _kdmesh

__all__ = [
    "mesh", "delaunay", "read_surface", "write_surface", "Mesh", "Error", "InputError", "SurfaceError",
    "GeometryError", "CheckError", "OutputError", "ResourceError", "UsageError", "CancelledError",
    "write_vtu", "write_msh", "write_inp", "write_medit", "write_boundary_vtu", "write_xdmf", "write_exodus", "write_nodes",
    "ORDERS",
]

ORDERS = tuple(_kdmesh.order_names())
NODE_KINDS = ("corner", "edge", "surface", "interior")


class Error(Exception):
    """A kdmesh error. `exit_code` is the CLI's exit code for it, `data` what the error carries,
    `summary` the job's summary (what was measured before the failure) when a job ran."""

    exit_code = 1

    def __init__(self, message, data=None, summary=None):
        super().__init__(message)
        self.data = dict(data or {})
        self.exit_code = int(self.data.get("exit_code", type(self).exit_code))
        self.summary = summary


class UsageError(Error, ValueError):
    """A bad option value (exit code 2)."""
    exit_code = 2


class InputError(Error):
    """A malformed or unreadable input (exit code 3): `file`, `line` (0: none)."""
    exit_code = 3

    @property
    def file(self):
        return self.data.get("file")

    @property
    def line(self):
        return self.data.get("line", 0)


class GeometryError(Error):
    """Input with no valid result (exit code 4); `where`: places (x, y, z) when the boundary
    could not be recovered."""
    exit_code = 4

    @property
    def where(self):
        w = self.data.get("where", [])
        return _np.asarray(w, dtype=float).reshape(-1, 3)


class SurfaceError(GeometryError):
    """A surface that bounds no solid (exit code 4): `facets`, the offending facet ids; for
    named bodies that touch or overlap also `bodies` (their two names) and `where` (a point
    where they meet, or one inside both)."""

    @property
    def facets(self):
        return list(self.data.get("facets", []))

    @property
    def bodies(self):
        return list(self.data.get("bodies", []))


class CheckError(Error):
    """A check failed: the mesh check, the boundary groups or a --check (exit code 5)."""
    exit_code = 5


class OutputError(Error):
    """An output could not be written (exit code 6): `file`, `reason`."""
    exit_code = 6

    @property
    def file(self):
        return self.data.get("file")


class ResourceError(Error):
    """The job would exceed its memory limit (exit code 7)."""
    exit_code = 7


class CancelledError(Error):
    """The job was cancelled by the `cancel` callable or its `timeout` (exit code 130)."""
    exit_code = 130


_CLASSES = {"usage": UsageError, "input": InputError, "geometry": GeometryError, "surface": SurfaceError,
            "check": CheckError, "output": OutputError, "resource": ResourceError, "cancelled": CancelledError}


def _error_class(data):
    return _CLASSES.get(data.get("type"), Error)


class Mesh:
    """A checked tet mesh: numpy arrays and the job's summary."""

    def __init__(self, native, summary):
        self._native = native
        self.stats = summary
        self._groups = None

    # The arrays are copied out of the C++ mesh when first asked for (a job that only writes
    # files copies nothing).
    @functools.cached_property
    def points(self):
        """(N, 3) float64 node coordinates."""
        return self._native.points

    @functools.cached_property
    def tets(self):
        """(M, 4) uint32 node ids per tet, positively oriented."""
        return self._native.tets

    @functools.cached_property
    def regions(self):
        """(M,) body id per tet."""
        return self._native.regions

    @functools.cached_property
    def boundary_faces(self):
        """(K, 3) uint32 node ids per boundary triangle, oriented outward."""
        return self._native.boundary_faces

    @functools.cached_property
    def node_kind(self):
        """(N,) uint8: 0 corner, 1 edge, 2 surface, 3 interior (NODE_KINDS)."""
        return self._native.node_kind

    @functools.cached_property
    def target_size(self):
        """(N,) float32: the sizing field at each node."""
        return self._native.target_size

    @property
    def groups(self):
        """name -> (dim, element ids): tets (dim 3), boundary faces (dim 2, rows of
        fe_faces) or feature-edge segments (dim 1, rows of fe_edges) of the group. Computed
        when groups, patch_groups, element_order 2 or a solver output were asked for;
        otherwise the bodies only (body_<i>, from the regions)."""
        if self._groups is None:
            n = self._native
            if n.has_fe:
                of = {3: n.fe_tet_entity, 2: n.fe_face_entity, 1: n.fe_edge_entity}
                self._groups = {name: (dim, _np.flatnonzero(_np.isin(of[dim], entities)).astype(_np.uint32))
                                for name, dim, entities in n.fe_groups}
            else:
                self._groups = {f"body_{b + 1}": (3, _np.flatnonzero(self.regions == b).astype(_np.uint32))
                                for b in _np.unique(self.regions)}
        return self._groups

    @property
    def fe_faces(self):
        return self._native.fe_faces

    @property
    def fe_edges(self):
        return self._native.fe_edges

    def to_meshio(self):
        """A meshio.Mesh: the tets and boundary triangles, point data node_kind and
        target_size, cell data region, and cell_sets for the groups."""
        import meshio
        faces = self.fe_faces if self._native.has_fe else self.boundary_faces
        cells = [("tetra", self.tets.astype(_np.int64)), ("triangle", faces[:, :3].astype(_np.int64))]
        empty = _np.zeros(0, dtype=_np.uint32)
        cell_sets = {}
        for name, (dim, ids) in self.groups.items():
            if dim == 3:
                cell_sets[name] = [ids, empty]
            elif dim == 2:
                cell_sets[name] = [empty, ids]
        return meshio.Mesh(self.points, cells,
                           point_data={"node_kind": self.node_kind.astype(_np.int32),
                                       "target_size": self.target_size.astype(_np.float64)},
                           cell_data={"region": [self.regions.astype(_np.int32),
                                                 _np.zeros(len(faces), dtype=_np.int32)]},
                           cell_sets=cell_sets)

    def __repr__(self):
        c = self.stats.get("counts", {})
        return f"<kdmesh.Mesh {c.get('nodes')} nodes, {c.get('tets')} tets>"


def _raise(err, summary):
    cls = _error_class(err)
    raise cls(err.get("message", ""), err, summary)


def mesh(surface, size, progress=None, cancel=None, **options):
    """Meshes the solid bounded by `surface`: a path (.stl, .ply, .obj, .off) or a pair
    (vertices (n, 3), triangles (m, 3)); or, with surface=None and
    bodies=[{"name": ..., "input": path}, ...], several named solids together (region k is
    body k). `size` and **options are a batch job's keys.
    `progress(stage, fraction)` is called during long stages; `cancel()` returning True stops
    the job (CancelledError). Ctrl-C stops it too and raises KeyboardInterrupt. The GIL is
    released while meshing."""
    opts = dict(options)
    opts["size"] = size
    if isinstance(surface, (tuple, list)):
        if len(surface) != 2:
            raise UsageError("surface must be a path or a (vertices, triangles) pair")
        surface = (_np.ascontiguousarray(surface[0], dtype=_np.float64),
                   _np.ascontiguousarray(surface[1], dtype=_np.int64))
    elif surface is not None:
        surface = str(surface)
    text = _json.dumps(opts, default=_json_default)
    native, summary_text, err, interrupted = _kdmesh.run(surface, text, progress, cancel)
    summary = _json.loads(summary_text)
    if interrupted:
        raise KeyboardInterrupt
    if err is not None:
        _raise(err, summary)
    return Mesh(native, summary)


def _json_default(x):
    if isinstance(x, _np.ndarray):
        return x.tolist()
    if isinstance(x, _np.generic):
        return x.item()
    raise TypeError(f"{type(x).__name__} is not an option value")


def delaunay(points, order="kd-bfs", threads=1, seed=1):
    """The Delaunay tetrahedralization of `points` (n, 3): (tets (m, 4) uint32, counters dict:
    inserted, orient_tests, conflicts, exact_fallbacks, duplicates, threads, seconds). `order`
    is one of ORDERS; the tets do not depend on it or on `threads`."""
    return _kdmesh.delaunay(_np.ascontiguousarray(points, dtype=_np.float64), order, int(threads), int(seed))


def read_surface(path):
    """(vertices (n, 3) float64, triangles (m, 3) uint32) of an STL, PLY, OBJ or OFF file."""
    return _kdmesh.read_surface(str(path))


def write_surface(path, vertices, triangles, binary=True):
    """Writes an STL or PLY surface (by extension)."""
    _kdmesh.write_surface(_np.ascontiguousarray(vertices, dtype=_np.float64),
                          _np.ascontiguousarray(triangles, dtype=_np.int64), str(path), bool(binary))


def _fe(m, what):
    if not m._native.has_fe:
        raise UsageError(f"{what} needs the boundary groups: mesh with groups=..., patch_groups=True or "
                         "element_order=2, or give the output in output={...}")
    return m._native


def write_vtu(m, path):
    m._native.write_vtu(str(path))


def write_nodes(m, path):
    m._native.write_nodes(str(path))


def write_msh(m, path, version="4.1"):
    _fe(m, "write_msh").write_msh(str(path), {"4.1": 41, "2.2": 22}[str(version)])


def write_inp(m, path):
    _fe(m, "write_inp").write_inp(str(path))


def write_medit(m, path):
    _fe(m, "write_medit").write_medit(str(path))


def write_boundary_vtu(m, path):
    _fe(m, "write_boundary_vtu").write_boundary_vtu(str(path))


def write_xdmf(m, path):
    """XDMF + HDF5 (the .h5 beside it) for dolfinx: grids "mesh", "cell_tags" (regions) and
    "facet_tags" (boundary faces, tagged by their first group's position + 1, else 0)."""
    _fe(m, "write_xdmf").write_xdmf(str(path))


def write_exodus(m, path):
    """Exodus II for MOOSE / ParaView: one element block per region, one side set per surface
    group, one node set per group (io/exodus_writer.h)."""
    _fe(m, "write_exodus").write_exodus(str(path))
