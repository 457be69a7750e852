// kdmesh — XDMF 3 + HDF5 writer for FeMesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// References: the XDMF 3 model and format (xdmf.org, "XDMF Model and Format"); the layout
// dolfinx 0.5 writes (cpp/dolfinx/io/xdmf_mesh.cpp, xdmf_meshtags.h) and reads
// (XDMFFile::read_mesh, read_meshtags: grids found by Name, topology and values DataItems read
// by their HDF5 path after the ':'; the HDF5 file is the XDMF file's name with extension .h5).
#include "io/xdmf_writer.h"

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/fe_mesh_index.h"
#include "io/file_io.h"
#include "io/xml_escape.h"

namespace kdmesh {

namespace {

/// HDF5 calls are serialised: a library build without thread safety must not be entered by two
/// jobs of one batch at once, and the error-printing switch below is process-wide.
std::mutex& hdf5_mutex() {
  static std::mutex m;
  return m;
}

/// Turns HDF5's automatic error printing (to stderr) off while alive; errors become
/// OutputErrors instead.
class QuietHdf5 {
 public:
  QuietHdf5() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }
  QuietHdf5(const QuietHdf5&) = delete;
  QuietHdf5& operator=(const QuietHdf5&) = delete;

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
};

/// An HDF5 identifier closed by `close` at scope exit.
class Hid {
 public:
  Hid(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Hid() {
    if (id_ >= 0) close_(id_);
  }
  Hid(const Hid&) = delete;
  Hid& operator=(const Hid&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }
  /// Closes now; false if closing failed.
  bool close() {
    const hid_t id = id_;
    id_ = -1;
    return close_(id) >= 0;
  }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

/// Creates the group `name` of `file` (its parent exists), without modification times.
void create_group(hid_t file, const char* name, const std::string& report_as) {
  Hid gcpl(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
  if (!gcpl.ok() || H5Pset_obj_track_times(gcpl.get(), 0) < 0)
    throw OutputError(report_as, std::string("HDF5: cannot set the properties of group ") + name);
  Hid group(H5Gcreate2(file, name, H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), H5Gclose);
  if (!group.ok() || !group.close()) throw OutputError(report_as, std::string("HDF5: cannot create group ") + name);
}

/// Writes `data` (rows x cols, or rows when cols == 0) as the dataset `name` (its group
/// exists) of `file`, stored as `file_type`.
template <class T>
void write_dataset(hid_t file, const std::string& name, hid_t mem_type, hid_t file_type,
                   const std::vector<T>& data, std::size_t rows, std::size_t cols,
                   const std::string& report_as) {
  auto fail = [&](const char* what) {
    throw OutputError(report_as, std::string("HDF5: cannot ") + what + " dataset " + name);
  };
  const hsize_t dims[2] = {hsize_t(rows), hsize_t(cols)};
  Hid space(H5Screate_simple(cols ? 2 : 1, dims, nullptr), H5Sclose);
  if (!space.ok()) fail("describe");
  // no modification times: the same mesh gives the same bytes
  Hid dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  if (!dcpl.ok() || H5Pset_obj_track_times(dcpl.get(), 0) < 0) fail("set the properties of");
  Hid set(H5Dcreate2(file, name.c_str(), file_type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
          H5Dclose);
  if (!set.ok()) fail("create");
  if (!data.empty() && H5Dwrite(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0)
    fail("write");
  if (!set.close()) fail("close");
}

std::vector<std::int64_t> widen(const std::vector<std::uint32_t>& v) {
  return std::vector<std::int64_t>(v.begin(), v.end());
}

/// The facet tag of every boundary face (see the header).
std::vector<std::int32_t> facet_tags(const FeMesh& mesh, const FeIndex& index) {
  const EntityTable& patches = index.dim[2];
  std::vector<std::int32_t> tag_of_patch(patches.size(), 0);
  for (std::size_t k = 0; k < patches.size(); ++k)
    if (patches.gstart[k] < patches.gstart[k + 1])
      tag_of_patch[k] = std::int32_t(patches.group_of[patches.gstart[k]] + 1);
  std::vector<std::int32_t> tags(mesh.face_entity.size());
  for (std::size_t f = 0; f < tags.size(); ++f) tags[f] = tag_of_patch[patches.find(mesh.face_entity[f])];
  return tags;
}

void write_hdf5(const FeMesh& mesh, const FeIndex& index, const std::string& h5_file) {
  const std::lock_guard<std::mutex> lock(hdf5_mutex());
  const QuietHdf5 quiet;
  // the temporary exists (created exclusively by AtomicFile): truncate it
  Hid file(H5Fcreate(h5_file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
  if (!file.ok()) throw OutputError(h5_file, "HDF5: cannot create the file");
  const hid_t f = file.get();
  for (const char* group : {"/Mesh", "/Mesh/mesh", "/MeshTags", "/MeshTags/cell_tags", "/MeshTags/facet_tags"})
    create_group(f, group, h5_file);
  write_dataset(f, "/Mesh/mesh/geometry", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, mesh.points.xyz,
                mesh.points.size(), 3, h5_file);
  write_dataset(f, "/Mesh/mesh/topology", H5T_NATIVE_INT64, H5T_STD_I64LE, widen(mesh.tets),
                mesh.num_tets(), std::size_t(mesh.tet_nodes()), h5_file);
  const std::vector<std::int32_t> regions(mesh.tet_entity.begin(), mesh.tet_entity.end());
  write_dataset(f, "/MeshTags/cell_tags/values", H5T_NATIVE_INT32, H5T_STD_I32LE, regions,
                regions.size(), 0, h5_file);
  write_dataset(f, "/MeshTags/facet_tags/topology", H5T_NATIVE_INT64, H5T_STD_I64LE, widen(mesh.faces),
                mesh.num_faces(), std::size_t(mesh.face_nodes()), h5_file);
  write_dataset(f, "/MeshTags/facet_tags/values", H5T_NATIVE_INT32, H5T_STD_I32LE, facet_tags(mesh, index),
                mesh.num_faces(), 0, h5_file);
  if (H5Fflush(f, H5F_SCOPE_GLOBAL) < 0 || !file.close())
    throw OutputError(h5_file, "HDF5: cannot flush and close the file");
}

std::string data_item(std::size_t rows, std::size_t cols, const char* number_type, int precision,
                      const std::string& h5_name, const char* dataset) {
  // appended piece by piece: `" " + std::to_string(cols)` makes GCC 12 warn falsely
  // (-Wrestrict, GCC bug 105329), as in core/error.h
  std::string s = "<DataItem Dimensions=\"";
  s += std::to_string(rows);
  if (cols) {
    s += ' ';
    s += std::to_string(cols);
  }
  s += "\" NumberType=\"";
  s += number_type;
  s += "\" Precision=\"";
  s += std::to_string(precision);
  s += "\" Format=\"HDF\">";
  s += h5_name;
  s += ':';
  s += dataset;
  s += "</DataItem>";
  return s;
}

std::string topology(const char* type, std::size_t n, std::size_t nodes, const std::string& h5_name,
                     const char* dataset) {
  return "      <Topology TopologyType=\"" + std::string(type) + "\" NumberOfElements=\"" + std::to_string(n) +
         "\" NodesPerElement=\"" + std::to_string(nodes) + "\">\n        " +
         data_item(n, nodes, "Int", 8, h5_name, dataset) + "\n      </Topology>\n";
}

std::string attribute(const char* name, std::size_t n, const std::string& h5_name, const char* dataset) {
  return "      <Attribute Name=\"" + std::string(name) + "\" AttributeType=\"Scalar\" Center=\"Cell\">\n        " +
         data_item(n, 0, "Int", 4, h5_name, dataset) + "\n      </Attribute>\n";
}

std::string xdmf_xml(const FeMesh& mesh, const std::string& h5_file_name) {
  const std::string h5 = xml_escape(h5_file_name);
  const bool p2 = mesh.order == 2;
  const char* tet_type = p2 ? "Tetrahedron_10" : "Tetrahedron";
  const char* tri_type = p2 ? "Triangle_6" : "Triangle";
  const std::size_t nt = mesh.num_tets(), nf = mesh.num_faces();
  const std::string tets = topology(tet_type, nt, std::size_t(mesh.tet_nodes()), h5, "/Mesh/mesh/topology");
  const std::string geometry_ref =
      "      <xi:include xpointer=\"xpointer(/Xdmf/Domain/Grid[@Name='mesh']/Geometry)\"/>\n";
  std::string x =
      "<?xml version=\"1.0\"?>\n"
      "<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n"
      "  <Domain>\n"
      "    <Grid Name=\"mesh\" GridType=\"Uniform\">\n" +
      tets +
      "      <Geometry GeometryType=\"XYZ\">\n        " +
      data_item(mesh.points.size(), 3, "Float", 8, h5, "/Mesh/mesh/geometry") +
      "\n      </Geometry>\n"
      "    </Grid>\n"
      "    <Grid Name=\"cell_tags\" GridType=\"Uniform\">\n" +
      geometry_ref + tets + attribute("cell_tags", nt, h5, "/MeshTags/cell_tags/values") +
      "    </Grid>\n"
      "    <Grid Name=\"facet_tags\" GridType=\"Uniform\">\n" +
      geometry_ref +
      topology(tri_type, nf, std::size_t(mesh.face_nodes()), h5, "/MeshTags/facet_tags/topology") +
      attribute("facet_tags", nf, h5, "/MeshTags/facet_tags/values");
  for (std::size_t g = 0; g < mesh.groups.size(); ++g)
    if (mesh.groups[g].dim == 2)  // names are [A-Za-z0-9_-] (index_fe_mesh): nothing to escape
      x += "      <Information Name=\"group\" Value=\"" + std::to_string(g + 1) + " " + mesh.groups[g].name +
           "\"/>\n";
  x += "    </Grid>\n  </Domain>\n</Xdmf>\n";
  return x;
}

}  // namespace

void write_xdmf_files(const FeMesh& mesh, const std::string& xml_file, const std::string& h5_file,
                      const std::string& h5_name) {
  const FeIndex index = index_fe_mesh(mesh, "write_xdmf");
  const EntityTable& regions = index.dim[3];
  if (!regions.ids.empty() && regions.ids.back() > std::uint32_t(std::numeric_limits<std::int32_t>::max()))
    throw UsageError("write_xdmf: region id " + std::to_string(regions.ids.back()) +
                     " exceeds 2^31 - 1: XDMF tags are int32");
  if (h5_name.find(':') != std::string::npos)
    throw UsageError("write_xdmf: the HDF5 file name '" + h5_name +
                     "' contains ':', which XDMF readers take as the file / dataset separator");
  write_hdf5(mesh, index, h5_file);
  FileWriter xml(xml_file, xml_file);
  const std::string text = xdmf_xml(mesh, h5_name);
  xml.write(text.data(), text.size());
  xml.close();
}

void write_xdmf(const FeMesh& mesh, const std::string& path) {
  const std::string h5 = xdmf_hdf5_path(path);
  if (h5 == path)
    throw UsageError("write_xdmf: '" + path + "' ends in .h5: its HDF5 file would be the XDMF file itself");
  AtomicFileSet files;
  const std::string xml_temp = files.add(path);
  const std::string h5_temp = files.add(h5);
  try {
    write_xdmf_files(mesh, xml_temp, h5_temp, std::filesystem::path(h5).filename().string());
  } catch (const OutputError& e) {
    if (e.file() == xml_temp) throw OutputError(path, e.reason());
    if (e.file() == h5_temp) throw OutputError(h5, e.reason());
    throw;
  }
  files.commit();
}

}  // namespace kdmesh
