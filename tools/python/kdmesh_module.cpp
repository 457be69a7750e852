// kdmesh — the Python module's native part (_kdmesh): a thin layer over the job runner
// (tools/app/mesh_job.h, itself over mesher/mesh_solid.h) and the Delaunay kernel. The
// options are the batch file's job keys, parsed by the same code (parse_job); errors come back
// as data and tools/python/kdmesh/__init__.py raises the Python exception classes from them.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <exception>
#include <filesystem>
#include <memory>
#include <string>

#include "core/timer.h"
#include "io/boundary_vtu_writer.h"
#include "io/inp_writer.h"
#include "io/medit_writer.h"
#include "io/exodus_writer.h"
#include "io/xdmf_writer.h"
#include "io/msh_writer.h"
#include "io/points_io.h"
#include "io/surface_io.h"
#include "io/vtu_writer.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/order/order.h"
#include "mesher/surface/surface_prepare.h"
#include "tools/app/job_config.h"
#include "tools/app/mesh_job.h"

namespace py = pybind11;
using namespace kdmesh;

namespace {

/// A finished job's mesh (its summary goes to Python separately, as JSON text).
struct PyMesh {
  MeshResult result;
  bool has_fe = false;
};

template <class T>
py::array_t<T> array_2d(const std::vector<T>& v, std::size_t cols) {
  py::array_t<T> a({v.size() / cols, cols});
  if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(T));
  return a;
}

template <class T>
py::array_t<T> array_1d(const std::vector<T>& v) {
  py::array_t<T> a(v.size());
  if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(T));
  return a;
}

/// (vertices (n, 3) float64, triangles (m, 3) integer) -> SurfaceMesh, ids checked.
SurfaceMesh surface_from_arrays(py::array_t<double, py::array::c_style | py::array::forcecast> v,
                                py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> f) {
  if (v.ndim() != 2 || v.shape(1) != 3) throw UsageError("vertices must be an (n, 3) array");
  if (f.ndim() != 2 || f.shape(1) != 3) throw UsageError("triangles must be an (m, 3) array");
  SurfaceMesh s;
  const std::size_t n = std::size_t(v.shape(0)), m = std::size_t(f.shape(0));
  s.points.xyz.assign(v.data(), v.data() + 3 * n);
  s.tris.resize(3 * m);
  const std::int64_t* ids = f.data();
  for (std::size_t k = 0; k < 3 * m; ++k) {
    if (ids[k] < 0 || std::uint64_t(ids[k]) >= n)
      throw UsageError("triangles[" + std::to_string(k / 3) + "] refers to vertex " + std::to_string(ids[k]) +
                       " of " + std::to_string(n));
    s.tris[k] = std::uint32_t(ids[k]);
  }
  return s;
}

/// The error of a failed job as data: type, exit code, message and what the error carries.
py::dict error_data(std::exception_ptr error) {
  py::dict d;
  try {
    std::rethrow_exception(error);
  } catch (const CancelledError& e) {
    d["type"] = "cancelled";
  } catch (const BodyContactError& e) {  // a SurfaceError with the two bodies and a point
    d["type"] = "surface";
    d["facets"] = e.facets();
    d["bodies"] = std::vector<std::string>{e.names()[0], e.names()[1]};
    d["where"] = std::vector<double>{e.where()[0], e.where()[1], e.where()[2]};
  } catch (const SurfaceError& e) {
    d["type"] = "surface";
    d["facets"] = e.facets();
  } catch (const BoundaryRecoveryError& e) {
    d["type"] = "geometry";
    d["where"] = e.where();
  } catch (const InputError& e) {
    d["type"] = "input";
    d["file"] = e.file();
    d["line"] = e.line();
  } catch (const OutputError& e) {
    d["type"] = "output";
    d["file"] = e.file();
    d["reason"] = e.reason();
  } catch (const Error& e) {
    d["type"] = error_type_name(e.code());
  } catch (...) {
    d["type"] = "internal";
  }
  return d;
}

/// Runs one job. Returns (PyMesh or None, summary JSON text, error dict or None, interrupted).
py::tuple run(py::object surface, const std::string& options_json, py::object progress, py::object cancel) {
  MeshJob job;
  try {
    job = parse_job(options_json, "kdmesh.mesh");
  } catch (const InputError& e) {  // in a batch file a bad key is a bad file; here a bad argument
    const std::string what = e.what();
    throw UsageError(what.substr(std::min(what.size(), e.file().size() + (e.line() ? 3 + std::to_string(e.line()).size() : 2))));
  }
  SurfaceMesh in_memory;
  bool have_arrays = false;
  if (!job.bodies.empty() || surface.is_none()) {  // bodies=[{name, input}, ...]: the files are read by the job
    if (job.bodies.empty()) throw UsageError("surface is None: give a path, (vertices, triangles) or bodies=[...]");
    if (!surface.is_none()) throw UsageError("give either a surface or bodies=[...], not both");
  } else if (py::isinstance<py::tuple>(surface) || py::isinstance<py::list>(surface)) {
    py::sequence seq = surface;
    if (py::len(seq) != 2) throw UsageError("surface must be a path or a (vertices, triangles) pair");
    using Vertices = py::array_t<double, py::array::c_style | py::array::forcecast>;
    using Triangles = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
    in_memory = surface_from_arrays(seq[0].cast<Vertices>(), seq[1].cast<Triangles>());
    have_arrays = true;
    if (job.input.empty()) job.input = "arrays";
  } else {
    job.input = py::str(surface);
    std::error_code ec;
    if (!std::filesystem::is_regular_file(job.input, ec))
      throw InputError(job.input, 0, "no such file");
  }
  const bool has_fe = has_solver_outputs(job) || !job.groups.empty() || job.group_options.patch_groups ||
                      job.element_order == 2 || !job.bodies.empty();  // named bodies: their volume groups
  // The job runner turns the boundary-groups stage on for solver outputs; the Python result
  // also carries them when groups (or quadratic elements) are asked for.
  job.fe_groups = has_fe;
  bool interrupted = false;
  const auto deadline = job.timeout > 0 ? std::chrono::steady_clock::now() + std::chrono::duration<double>(job.timeout)
                                         : std::chrono::steady_clock::time_point::max();
  MeshCallbacks cb;
  if (!progress.is_none())
    cb.progress = [&](const std::string& stage, double f) {
      py::gil_scoped_acquire gil;
      progress(stage, f);
    };
  cb.cancel = [&]() -> bool {
    if (std::chrono::steady_clock::now() > deadline) return true;
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) {  // Ctrl-C: cancel the job, raise KeyboardInterrupt after
      PyErr_Clear();
      interrupted = true;
      return true;
    }
    return !cancel.is_none() && py::bool_(cancel());
  };
  auto out = std::make_unique<PyMesh>();
  nlohmann::json summary;
  py::object err = py::none();
  {
    py::gil_scoped_release release;
    Stopwatch clock;
    try {
      out->result = run_job(job, cb, summary, have_arrays ? &in_memory : nullptr);
      out->has_fe = has_fe;
    } catch (...) {
      const std::exception_ptr e = std::current_exception();
      record_failure(summary, e, clock.seconds());
      py::gil_scoped_acquire gil;
      py::dict d = error_data(e);
      d["exit_code"] = summary["error"].value("exit_code", 1);
      d["message"] = summary["error"].value("message", std::string());
      if (std::chrono::steady_clock::now() > deadline && d["type"].cast<std::string>() == "cancelled")
        d["timeout"] = job.timeout;
      err = d;
    }
  }
  py::object mesh = err.is_none() ? py::cast(std::move(out)) : py::object(py::none());
  return py::make_tuple(mesh, summary.dump(), err, interrupted);
}

py::tuple delaunay_tets(py::array_t<double, py::array::c_style | py::array::forcecast> points,
                        const std::string& order, unsigned threads, std::uint64_t seed) {
  if (points.ndim() != 2 || points.shape(1) != 3) throw UsageError("points must be an (n, 3) array");
  PointSet pts;
  pts.xyz.assign(points.data(), points.data() + 3 * points.shape(0));
  OrderOptions oo;
  oo.kind = parse_order_kind(order);
  oo.seed = seed;
  oo.threads = threads == 1 ? 1 : 0;
  DelaunayOptions dopt;
  dopt.threads = threads;
  DelaunayResult r;
  {
    py::gil_scoped_release release;
    r = delaunay(pts, make_order(pts, oo), dopt);
  }
  const std::vector<std::uint32_t> tets = finite_tets(r.tri);
  py::dict stats;
  stats["inserted"] = r.stats.inserted;
  stats["orient_tests"] = r.stats.orient_tests;
  stats["conflicts"] = r.stats.conflicts;
  stats["exact_fallbacks"] = r.stats.exact_fallbacks;
  stats["duplicates"] = r.stats.duplicates.size();
  stats["threads"] = r.stats.threads;
  stats["seconds"] = r.stats.seconds;
  return py::make_tuple(array_2d(tets, 4), stats);
}

}  // namespace

PYBIND11_MODULE(_kdmesh, m) {
  m.doc() = "kdmesh native module (use the kdmesh package)";
  py::class_<PyMesh>(m, "NativeMesh")
      .def_property_readonly("points", [](const PyMesh& p) { return array_2d(p.result.mesh.nodes.points.xyz, 3); })
      .def_property_readonly("tets", [](const PyMesh& p) { return array_2d(p.result.mesh.tets, 4); })
      .def_property_readonly("regions", [](const PyMesh& p) { return array_1d(p.result.mesh.tet_region); })
      .def_property_readonly("boundary_faces", [](const PyMesh& p) { return array_2d(p.result.mesh.boundary, 3); })
      .def_property_readonly("node_kind", [](const PyMesh& p) {
        std::vector<std::uint8_t> k(p.result.mesh.nodes.kind.size());
        for (std::size_t i = 0; i < k.size(); ++i) k[i] = std::uint8_t(p.result.mesh.nodes.kind[i]);
        return array_1d(k);
      })
      .def_property_readonly("target_size", [](const PyMesh& p) { return array_1d(p.result.mesh.nodes.size); })
      .def_property_readonly("has_fe", [](const PyMesh& p) { return p.has_fe; })
      .def_property_readonly("fe_faces", [](const PyMesh& p) { return array_2d(p.result.fe.faces, std::size_t(p.result.fe.face_nodes())); })
      .def_property_readonly("fe_face_entity", [](const PyMesh& p) { return array_1d(p.result.fe.face_entity); })
      .def_property_readonly("fe_tet_entity", [](const PyMesh& p) { return array_1d(p.result.fe.tet_entity); })
      .def_property_readonly("fe_edges", [](const PyMesh& p) { return array_2d(p.result.fe.edges, std::size_t(p.result.fe.edge_nodes())); })
      .def_property_readonly("fe_edge_entity", [](const PyMesh& p) { return array_1d(p.result.fe.edge_entity); })
      .def_property_readonly("fe_groups", [](const PyMesh& p) {
        py::list out;
        for (const FeGroup& g : p.result.fe.groups) out.append(py::make_tuple(g.name, g.dim, g.entities));
        return out;
      })
      .def("write_vtu", [](const PyMesh& p, const std::string& path) { write_vtu(p.result.tet_mesh, path); })
      .def("write_nodes", [](const PyMesh& p, const std::string& path) { write_xyz(p.result.mesh.nodes.points, path); })
      .def("write_msh", [](const PyMesh& p, const std::string& path, int version) {
        MshOptions o;
        o.version = version;
        write_msh(p.result.fe, path, o);
      })
      .def("write_inp", [](const PyMesh& p, const std::string& path) { write_inp(p.result.fe, path); })
      .def("write_medit", [](const PyMesh& p, const std::string& path) { write_medit(p.result.fe, path); })
      .def("write_boundary_vtu", [](const PyMesh& p, const std::string& path) { write_boundary_vtu(p.result.fe, path); })
      .def("write_xdmf", [](const PyMesh& p, const std::string& path) { write_xdmf(p.result.fe, path); })
      .def("write_exodus", [](const PyMesh& p, const std::string& path) { write_exodus(p.result.fe, path); });
  m.def("run", &run, py::arg("surface"), py::arg("options_json"), py::arg("progress"), py::arg("cancel"));
  m.def("delaunay", &delaunay_tets, py::arg("points"), py::arg("order"), py::arg("threads"), py::arg("seed"));
  m.def("read_surface", [](const std::string& path) {
    const SurfaceMesh s = read_surface(path);
    return py::make_tuple(array_2d(s.points.xyz, 3), array_2d(s.tris, 3));
  });
  m.def("write_surface", [](py::array_t<double, py::array::c_style | py::array::forcecast> v,
                            py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> f,
                            const std::string& path, bool binary) {
    const SurfaceMesh s = surface_from_arrays(v, f);
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".stl") write_stl(s, path, binary);
    else if (ext == ".ply") write_ply(s, path, binary);
    else throw UsageError(path + ": write_surface writes .stl or .ply");
  });
  m.def("order_names", &order_kind_names);
  // Errors raised before a job runs (bad options, unreadable arrays): their data travel in
  // the Python exception's arguments (type, exit code, message, data), see __init__.py.
  py::register_exception_translator([](std::exception_ptr p) {
    if (!p) return;
    try {
      std::rethrow_exception(p);
    } catch (const Error& e) {
      py::dict d = error_data(p);
      d["exit_code"] = int(e.code());
      d["message"] = std::string(e.what());
      py::object cls = py::module_::import("kdmesh").attr("_error_class")(d);
      PyErr_SetObject(cls.ptr(), py::make_tuple(std::string(e.what()), d).ptr());
    }
  });
}
