// Tests of the XDMF + HDF5 writer (io/xdmf_writer.h): the XML's grids and datasets, the
// HDF5 data read back with the HDF5 C library, atomic writes and errors. The real client
// (dolfinx) reads it in tests/python/test_xdmf_dolfinx.py.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/fe_mesh.h"
#include "io/xdmf_writer.h"
#include "tests/support/clients.h"
#include "tests/support/fe_cube.h"
#include "tests/support/scratch.h"

namespace kdmesh {
namespace {

namespace fs = std::filesystem;
using namespace test;

std::string scratch(const std::string& ext) { return scratch_path("io_xdmf", ext); }

/// An HDF5 dataset read whole, with its shape.
template <class T>
struct Dataset {
  std::vector<hsize_t> dims;
  std::vector<T> data;
};

template <class T>
Dataset<T> read_dataset(const std::string& file, const std::string& name, hid_t mem_type) {
  Dataset<T> d;
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(f, 0) << file;
  if (f < 0) return d;
  const hid_t set = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
  EXPECT_GE(set, 0) << name;
  if (set >= 0) {
    const hid_t space = H5Dget_space(set);
    d.dims.resize(std::size_t(H5Sget_simple_extent_ndims(space)));
    H5Sget_simple_extent_dims(space, d.dims.data(), nullptr);
    d.data.resize(std::size_t(H5Sget_simple_extent_npoints(space)));
    if (!d.data.empty()) {
      EXPECT_GE(H5Dread(set, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, d.data.data()), 0);
    }
    H5Sclose(space);
    H5Dclose(set);
  }
  H5Fclose(f);
  return d;
}

/// Every "<h5 file>:<dataset>" DataItem of the XML with its Dimensions attribute.
std::map<std::string, std::string> data_items(const std::string& xml) {
  std::map<std::string, std::string> items;
  const std::regex item("<DataItem Dimensions=\"([0-9 ]+)\"[^>]*Format=\"HDF\">([^<]+)</DataItem>");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), item); it != std::sregex_iterator(); ++it)
    items[(*it)[2]] = (*it)[1];
  return items;
}

std::string dims_text(const std::vector<hsize_t>& dims) {
  std::string s;
  for (const hsize_t d : dims) {
    if (!s.empty()) s += ' ';
    s += std::to_string(d);
  }
  return s;
}

TEST(XdmfFormat, XmlIsWellFormedAndNamesTheDatasetsWithTheirShapes) {
  for (int order : {1, 2}) {
    const FeMesh mesh = cube_mesh(2, order);
    const std::string path = scratch(".xdmf");
    write_xdmf(mesh, path);
    const std::string h5 = xdmf_hdf5_path(path);
    ASSERT_EQ(fs::path(h5).extension(), ".h5");
    ASSERT_TRUE(fs::is_regular_file(h5));
    const std::string xml = read_text(path);
    // well-formed XML (Debian's python3 is a build dependency)
    EXPECT_EQ(std::system(("/usr/bin/python3 -c \"import sys, xml.etree.ElementTree as E; E.parse(sys.argv[1])\" '" +
                           path + "'").c_str()),
              0);
    // the grids dolfinx reads by name, and the cell types of both orders
    for (const char* grid : {"Name=\"mesh\"", "Name=\"cell_tags\"", "Name=\"facet_tags\""})
      EXPECT_NE(xml.find(grid), std::string::npos) << grid;
    EXPECT_NE(xml.find(order == 2 ? "TopologyType=\"Tetrahedron_10\"" : "TopologyType=\"Tetrahedron\""),
              std::string::npos);
    EXPECT_NE(xml.find(order == 2 ? "TopologyType=\"Triangle_6\"" : "TopologyType=\"Triangle\""), std::string::npos);
    EXPECT_NE(xml.find("<Information Name=\"group\" Value=\"3 xmin\"/>"), std::string::npos);
    // every DataItem names an existing dataset of the HDF5 file, with its shape
    const auto items = data_items(xml);
    const std::string prefix = fs::path(h5).filename().string() + ":";
    const std::set<std::string> expected = {"/Mesh/mesh/geometry", "/Mesh/mesh/topology", "/MeshTags/cell_tags/values",
                                            "/MeshTags/facet_tags/topology", "/MeshTags/facet_tags/values"};
    std::set<std::string> named;
    for (const auto& [ref, dims] : items) {
      ASSERT_EQ(ref.rfind(prefix, 0), 0u) << ref;
      const std::string name = ref.substr(prefix.size());
      named.insert(name);
      const auto d = read_dataset<double>(h5, name, H5T_NATIVE_DOUBLE);
      EXPECT_EQ(dims_text(d.dims), dims) << name;
    }
    EXPECT_EQ(named, expected);
    const std::size_t nt = mesh.num_tets(), nf = mesh.num_faces();
    EXPECT_EQ(items.at(prefix + "/Mesh/mesh/geometry"), std::to_string(mesh.points.size()) + " 3");
    EXPECT_EQ(items.at(prefix + "/Mesh/mesh/topology"), std::to_string(nt) + " " + std::to_string(mesh.tet_nodes()));
    EXPECT_EQ(items.at(prefix + "/MeshTags/cell_tags/values"), std::to_string(nt));
    EXPECT_EQ(items.at(prefix + "/MeshTags/facet_tags/topology"),
              std::to_string(nf) + " " + std::to_string(mesh.face_nodes()));
    EXPECT_EQ(items.at(prefix + "/MeshTags/facet_tags/values"), std::to_string(nf));
  }
}

TEST(XdmfFormat, CubeRoundTripsThroughHdf5) {
  const FeMesh mesh = cube_mesh(2, 1);
  const std::string path = scratch(".xdmf");
  write_xdmf(mesh, path);
  const std::string h5 = xdmf_hdf5_path(path);

  const auto geometry = read_dataset<double>(h5, "/Mesh/mesh/geometry", H5T_NATIVE_DOUBLE);
  ASSERT_EQ(geometry.dims, (std::vector<hsize_t>{mesh.points.size(), 3}));
  EXPECT_EQ(geometry.data, mesh.points.xyz);
  // a known node: (i, j, k) = (1, 2, 0) of the 3 x 3 x 3 grid is point 1 + 3 * 2 = 7
  EXPECT_EQ(geometry.data[3 * 7 + 0], 0.5);
  EXPECT_EQ(geometry.data[3 * 7 + 1], 1.0);
  EXPECT_EQ(geometry.data[3 * 7 + 2], 0.0);

  const auto topology = read_dataset<std::int64_t>(h5, "/Mesh/mesh/topology", H5T_NATIVE_INT64);
  ASSERT_EQ(topology.dims, (std::vector<hsize_t>{mesh.num_tets(), 4}));
  EXPECT_EQ(topology.data, std::vector<std::int64_t>(mesh.tets.begin(), mesh.tets.end()));

  const auto cells = read_dataset<std::int32_t>(h5, "/MeshTags/cell_tags/values", H5T_NATIVE_INT32);
  ASSERT_EQ(cells.data.size(), mesh.num_tets());
  EXPECT_EQ(cells.data, std::vector<std::int32_t>(mesh.tet_entity.begin(), mesh.tet_entity.end()));
  EXPECT_EQ(std::set<std::int32_t>(cells.data.begin(), cells.data.end()),
            (std::set<std::int32_t>{std::int32_t(kLeftVolume), std::int32_t(kRightVolume)}));

  // facet tags: every face of mesh.faces (48 on the boundary of the 2x2x2 cube, plus the 8 of
  // the interface entity); tag = first dim-2 group listing the face's patch, + 1
  const auto faces = read_dataset<std::int64_t>(h5, "/MeshTags/facet_tags/topology", H5T_NATIVE_INT64);
  const auto tags = read_dataset<std::int32_t>(h5, "/MeshTags/facet_tags/values", H5T_NATIVE_INT32);
  ASSERT_EQ(faces.dims, (std::vector<hsize_t>{mesh.num_faces(), 3}));
  ASSERT_EQ(tags.data.size(), mesh.num_faces());
  EXPECT_EQ(mesh.num_faces(), 6u * 8u + 8u);
  EXPECT_EQ(faces.data, std::vector<std::int64_t>(mesh.faces.begin(), mesh.faces.end()));
  // groups: 0 solid, 1 right_half, 2..7 the sides, 8 sides (all six: a later, second group),
  // 9 interface
  std::map<std::int32_t, int> per_tag;
  for (std::size_t f = 0; f < tags.data.size(); ++f) {
    const std::uint32_t e = mesh.face_entity[f];
    const std::int32_t expected = e == kInterface ? 10 : std::int32_t(e - kSide0) + 3;
    EXPECT_EQ(tags.data[f], expected) << "face " << f;
    ++per_tag[tags.data[f]];
  }
  EXPECT_EQ(per_tag.size(), 7u);
  for (std::int32_t t = 3; t <= 8; ++t) EXPECT_EQ(per_tag[t], 8) << t;
}

TEST(XdmfFormat, FacesInNoGroupGetTagZero) {
  FeMesh mesh = cube_mesh(2, 1);
  mesh.groups.erase(mesh.groups.begin() + 2);  // xmin: its faces are still in "sides"
  mesh.groups.erase(mesh.groups.begin() + 7);  // "sides" (now at 7): xmin's faces in no group
  const std::string path = scratch(".xdmf");
  write_xdmf(mesh, path);
  const auto tags = read_dataset<std::int32_t>(xdmf_hdf5_path(path), "/MeshTags/facet_tags/values", H5T_NATIVE_INT32);
  ASSERT_EQ(tags.data.size(), mesh.num_faces());
  for (std::size_t f = 0; f < tags.data.size(); ++f)
    EXPECT_EQ(tags.data[f] == 0, mesh.face_entity[f] == kSide0) << "face " << f;
}

TEST(XdmfFormat, HdfFileNameFollowsDolfinx) {
  EXPECT_EQ(xdmf_hdf5_path("out/a.xdmf"), "out/a.h5");
  EXPECT_EQ(xdmf_hdf5_path("a.b.xdmf"), "a.b.h5");
  EXPECT_EQ(xdmf_hdf5_path("a"), "a.h5");
  EXPECT_THROW(write_xdmf(cube_mesh(2, 1), scratch(".h5")), UsageError);
}

TEST(XdmfFormat, UnwritablePathThrowsOutputErrorAndLeavesNoTemporary) {
  const FeMesh mesh = cube_mesh(2, 1);
  // a directory that cannot be written (root ignores permissions: use a missing directory
  // then, and a read-only one only when not root)
  const fs::path dir = scratch("-dir");  // removed first: reruns start clean
  fs::create_directories(dir);
  expect_unwritable_refused<OutputError>(dir, "m.xdmf",
                                         [&](const std::string& p) { write_xdmf(mesh, p); });
  // the HDF5 file's place is a directory: refused, the XDMF file not written either, and no
  // temporary left behind
  const std::string path = (dir / "m.xdmf").string();
  fs::create_directories(dir / "m.h5");
  try {
    write_xdmf(mesh, path);
    FAIL() << "no OutputError";
  } catch (const OutputError& e) {
    EXPECT_EQ(e.file(), (dir / "m.h5").string());
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_EQ(temporaries_in(dir), 0);
  // a symbolic link in the XDMF file's place is never replaced
  fs::remove(dir / "m.h5");
  fs::create_symlink("elsewhere.xdmf", path);
  EXPECT_THROW(write_xdmf(mesh, path), OutputError);
  EXPECT_TRUE(fs::is_symlink(path));
  EXPECT_EQ(temporaries_in(dir), 0);
}

TEST(XdmfFormat, ReplacesRegularFilesAtomically) {
  const FeMesh mesh = cube_mesh(2, 1);
  const std::string path = scratch(".xdmf");
  write_text_file(path, "old");
  write_text_file(xdmf_hdf5_path(path), "old");
  write_xdmf(mesh, path);
  EXPECT_NE(read_text(path), "old");
  EXPECT_EQ(read_dataset<double>(xdmf_hdf5_path(path), "/Mesh/mesh/geometry", H5T_NATIVE_DOUBLE).data.size(),
            mesh.points.xyz.size());
  EXPECT_EQ(temporaries_in(fs::path(path).parent_path()), 0);
}

TEST(XdmfFormat, InvalidMeshIsAUsageError) {
  FeMesh mesh = cube_mesh(2, 1);
  mesh.tets[5] = std::uint32_t(mesh.points.size());  // node id out of range
  EXPECT_THROW(write_xdmf(mesh, scratch(".xdmf")), UsageError);
}

}  // namespace
}  // namespace kdmesh
