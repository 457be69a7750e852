// SPDX-License-Identifier: AGPL-3.0-or-later
// VTU writer: what VTK's own reader gets back, the on-disk encoding, and failure behaviour.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkIdList.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkTypeInt32Array.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>
#include <zlib.h>

#include <bit>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "tests/support/scratch.h"
#include "core/tet_mesh.h"
#include "io/vtu_writer.h"

namespace kdmesh {
namespace {

namespace fs = std::filesystem;

std::string scratch(const std::string& ext) { return test::scratch_path("io_vtu", ext); }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Files in `path`'s directory whose names start with `path`'s file name followed by ".tmp".
std::vector<std::string> leftover_temps(const std::string& path) {
  std::vector<std::string> found;
  const fs::path p(path);
  if (!fs::exists(p.parent_path())) return found;
  const std::string prefix = p.filename().string() + ".tmp";
  for (const auto& entry : fs::directory_iterator(p.parent_path()))
    if (entry.path().filename().string().rfind(prefix, 0) == 0)
      found.push_back(entry.path().string());
  return found;
}

std::uint64_t bits(double d) { return std::bit_cast<std::uint64_t>(d); }

/// Five points, two positively oriented tets sharing a face, and data arrays of both kinds.
TetMesh small_mesh() {
  TetMesh m;
  m.points.push_back(0, 0, 0);
  m.points.push_back(1, 0, 0);
  m.points.push_back(0, 1, 0);
  m.points.push_back(0, 0, 1);
  m.points.push_back(1.0 / 3.0, 1e-300, -1.25);
  m.tets = {0, 1, 2, 3, 0, 2, 1, 4};
  m.point_data.push_back({"id", {10, -20, 30, std::numeric_limits<std::int32_t>::min(), 50}, {}});
  m.point_data.push_back(
      {"height", {}, {0.1 + 0.2, -0.0, 1e300, std::numeric_limits<double>::denorm_min(), 7}});
  m.cell_data.push_back({"region", {1, std::numeric_limits<std::int32_t>::max()}, {}});
  m.cell_data.push_back({"quality", {}, {1.0 / 3.0, 2.0 / 3.0}});
  m.cell_data.push_back({"angle", {}, {}, {1.0f / 3.0f, -std::numeric_limits<float>::denorm_min()}});
  return m;
}

/// A random mesh with `n` points and about 5n tets (random ids: enough to exercise sizes).
TetMesh random_mesh(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  TetMesh m;
  m.points.xyz.resize(3 * n);
  for (double& x : m.points.xyz) x = u(rng);
  m.tets.resize(4 * 5 * n);
  for (std::uint32_t& v : m.tets) v = std::uint32_t(rng() % n);
  return m;
}

vtkSmartPointer<vtkUnstructuredGrid> read_back(const std::string& path) {
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  EXPECT_EQ(reader->GetErrorCode(), 0u);
  return reader->GetOutput();
}

/// `got` holds exactly `want` (same type, name, values bit for bit).
void expect_array(vtkDataArray* got, const DataArray& want) {
  ASSERT_NE(got, nullptr) << "array '" << want.name << "' missing";
  EXPECT_EQ(got->GetNumberOfComponents(), 1);
  if (want.reals.empty() && !want.floats.empty()) {
    auto* f = vtkFloatArray::SafeDownCast(got);
    ASSERT_NE(f, nullptr) << want.name << " is " << got->GetClassName() << ", expected vtkFloatArray";
    ASSERT_EQ(std::size_t(f->GetNumberOfTuples()), want.floats.size());
    for (std::size_t i = 0; i < want.floats.size(); ++i)
      EXPECT_EQ(std::bit_cast<std::uint32_t>(f->GetValue(vtkIdType(i))), std::bit_cast<std::uint32_t>(want.floats[i]))
          << want.name << "[" << i << "]";
  } else if (!want.reals.empty()) {
    auto* d = vtkDoubleArray::SafeDownCast(got);
    ASSERT_NE(d, nullptr) << want.name << " is " << got->GetClassName()
                          << ", expected vtkDoubleArray";
    ASSERT_EQ(std::size_t(d->GetNumberOfTuples()), want.reals.size());
    for (std::size_t i = 0; i < want.reals.size(); ++i)
      EXPECT_EQ(bits(d->GetValue(vtkIdType(i))), bits(want.reals[i]))
          << want.name << "[" << i << "]";
  } else {
    auto* a = vtkIntArray::SafeDownCast(got);
    ASSERT_NE(a, nullptr) << want.name << " is " << got->GetClassName() << ", expected vtkIntArray";
    ASSERT_EQ(std::size_t(a->GetNumberOfTuples()), want.ints.size());
    for (std::size_t i = 0; i < want.ints.size(); ++i)
      EXPECT_EQ(a->GetValue(vtkIdType(i)), want.ints[i]) << want.name << "[" << i << "]";
  }
}

/// What VTK reads from `path` equals `m`: points, tets (as VTK_TETRA) and every data array.
void expect_same_mesh(const std::string& path, const TetMesh& m) {
  const auto grid = read_back(path);
  ASSERT_NE(grid, nullptr);
  ASSERT_EQ(std::size_t(grid->GetNumberOfPoints()), m.points.size());
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); ++i) {
    double p[3];
    grid->GetPoint(i, p);
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(bits(p[k]), bits(m.points.xyz[3 * i + k])) << "point " << i;
  }
  EXPECT_EQ(grid->GetPoints()->GetDataType(), VTK_DOUBLE);
  ASSERT_EQ(std::size_t(grid->GetNumberOfCells()), m.num_tets());
  vtkNew<vtkIdList> ids;
  for (vtkIdType t = 0; t < grid->GetNumberOfCells(); ++t) {
    EXPECT_EQ(grid->GetCellType(t), VTK_TETRA);
    grid->GetCellPoints(t, ids);
    ASSERT_EQ(ids->GetNumberOfIds(), 4);
    for (vtkIdType k = 0; k < 4; ++k)
      EXPECT_EQ(ids->GetId(k), vtkIdType(m.tets[4 * t + k])) << "tet " << t;
  }
  EXPECT_EQ(std::size_t(grid->GetPointData()->GetNumberOfArrays()), m.point_data.size());
  EXPECT_EQ(std::size_t(grid->GetCellData()->GetNumberOfArrays()), m.cell_data.size());
  for (const DataArray& a : m.point_data)
    expect_array(grid->GetPointData()->GetArray(a.name.c_str()), a);
  for (const DataArray& a : m.cell_data)
    expect_array(grid->GetCellData()->GetArray(a.name.c_str()), a);
}

TEST(Vtu, SmallMeshReadsBackExactly) {
  const TetMesh m = small_mesh();
  const std::string path = scratch(".vtu");
  write_vtu(m, path);
  expect_same_mesh(path, m);
  EXPECT_TRUE(leftover_temps(path).empty());
}

TEST(Vtu, RandomMeshReadsBackExactly) {
  TetMesh m = random_mesh(20000, 3);
  m.cell_data.push_back({"tet", {}, {}});
  for (std::size_t t = 0; t < m.num_tets(); ++t) m.cell_data.back().ints.push_back(std::int32_t(t));
  const std::string path = scratch(".vtu");
  write_vtu(m, path);
  expect_same_mesh(path, m);
}

/// The appended data (everything after the '_' that opens it) of the VTU file `text`.
std::string appended_data(const std::string& text) {
  const std::size_t tag = text.find("<AppendedData");
  EXPECT_NE(tag, std::string::npos);
  return text.substr(text.find('_', tag) + 1);
}

/// What VTK's own vtkXMLUnstructuredGridWriter writes for `m`, set up as kdmesh's writer was
/// until it compressed the blocks itself: raw appended, zlib level 1, UInt64 headers, Int32
/// cells, the data arrays in mesh order.
std::string vtk_writer_output(const TetMesh& m) {
  vtkNew<vtkUnstructuredGrid> grid;
  vtkNew<vtkDoubleArray> coords;
  coords->SetNumberOfComponents(3);
  coords->SetNumberOfTuples(vtkIdType(m.points.size()));
  std::copy(m.points.xyz.begin(), m.points.xyz.end(), coords->GetPointer(0));
  vtkNew<vtkPoints> points;
  points->SetData(coords);
  grid->SetPoints(points);
  vtkNew<vtkTypeInt32Array> offsets, conn;
  offsets->SetNumberOfValues(vtkIdType(m.num_tets() + 1));
  for (std::size_t t = 0; t <= m.num_tets(); ++t) offsets->SetValue(vtkIdType(t), std::int32_t(4 * t));
  conn->SetNumberOfValues(vtkIdType(m.tets.size()));
  std::copy(m.tets.begin(), m.tets.end(), conn->GetPointer(0));
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, conn);
  grid->SetCells(VTK_TETRA, cells);
  const auto add = [](vtkDataSetAttributes* to, const DataArray& a) {
    vtkSmartPointer<vtkDataArray> arr;
    if (!a.reals.empty()) {
      auto d = vtkSmartPointer<vtkDoubleArray>::New();
      for (double x : a.reals) d->InsertNextValue(x);
      arr = d;
    } else if (!a.floats.empty()) {
      auto d = vtkSmartPointer<vtkFloatArray>::New();
      for (float x : a.floats) d->InsertNextValue(x);
      arr = d;
    } else {
      auto d = vtkSmartPointer<vtkIntArray>::New();
      for (int x : a.ints) d->InsertNextValue(x);
      arr = d;
    }
    arr->SetName(a.name.c_str());
    to->AddArray(arr);
  };
  for (const DataArray& a : m.point_data) add(grid->GetPointData(), a);
  for (const DataArray& a : m.cell_data) add(grid->GetCellData(), a);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->WriteToOutputStringOn();
  writer->SetInputData(grid);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writer->SetCompressorTypeToZLib();
  writer->SetCompressionLevel(1);
  writer->SetHeaderTypeToUInt64();
  EXPECT_EQ(writer->Write(), 1);
  return writer->GetOutputString();
}

/// One appended array of a VTU file as its header describes it: the block size, the size of a
/// partial last block (0 if none), and the decoded bytes of its blocks in order.
struct DecodedArray {
  std::uint64_t block_size = 0, last_size = 0, blocks = 0;
  std::string bytes;
};

/// Every appended array of the VTU file `text` (UInt64 headers, zlib blocks), in the order of
/// their offsets in the XML, each block decoded with zlib's own inflate.
std::vector<DecodedArray> decoded_arrays(const std::string& text) {
  const std::string data = appended_data(text);
  const std::string xml = text.substr(0, text.find("<AppendedData"));
  std::vector<DecodedArray> out;
  const auto u64 = [&](std::size_t at) {
    std::uint64_t v = 0;
    for (int k = 7; k >= 0; --k) v = v << 8 | static_cast<unsigned char>(data.at(at + std::size_t(k)));
    return v;
  };
  for (std::size_t at = xml.find("offset=\""); at != std::string::npos; at = xml.find("offset=\"", at + 1)) {
    std::size_t p = std::stoull(xml.substr(at + 8));
    DecodedArray a;
    a.blocks = u64(p), a.block_size = u64(p + 8), a.last_size = u64(p + 16);
    std::size_t body = p + 24 + 8 * a.blocks;
    for (std::uint64_t b = 0; b < a.blocks; ++b) {
      const std::uint64_t packed = u64(p + 24 + 8 * b);
      const bool last = b + 1 == a.blocks && a.last_size != 0;
      std::string raw(last ? a.last_size : a.block_size, '\0');
      uLongf len = uLongf(raw.size());
      EXPECT_EQ(uncompress(reinterpret_cast<Bytef*>(raw.data()), &len,
                           reinterpret_cast<const Bytef*>(data.data() + body), uLong(packed)),
                Z_OK);
      EXPECT_EQ(len, raw.size());
      a.bytes += raw;
      body += packed;
    }
    out.push_back(std::move(a));
  }
  return out;
}

// The writer compresses its blocks on all cores, with libdeflate (zlib for the offsets and
// types); the blocks decode to the bytes VTK's own (one-thread, zlib) writer compresses, block
// for block: the same arrays, block sizes and partial last blocks. 4096 points: the points and
// connectivity fill their last 32 KiB block exactly (a partial-last-block size of 0); the data
// arrays end in partial blocks.
TEST(Vtu, AppendedBlocksDecodeToWhatVtksOwnWriterCompresses) {
  for (const std::size_t n : {std::size_t(4096), std::size_t(20011)}) {
    TetMesh m = random_mesh(n, 11);
    m.point_data.push_back({"id", {}, {}});
    for (std::size_t i = 0; i < n; ++i) m.point_data.back().ints.push_back(std::int32_t(i % 97) - 40);
    m.cell_data.push_back({"q", {}, {}});
    for (std::size_t t = 0; t < m.num_tets(); ++t) m.cell_data.back().reals.push_back(std::sin(double(t)));
    m.cell_data.push_back({"q32", {}, {}});
    for (std::size_t t = 0; t < m.num_tets(); ++t) m.cell_data.back().floats.push_back(float(std::cos(double(t))));
    const std::string path = scratch(".vtu");
    write_vtu(m, path);
    const std::vector<DecodedArray> ours = decoded_arrays(slurp(path)), vtks = decoded_arrays(vtk_writer_output(m));
    ASSERT_EQ(ours.size(), 7u) << n;  // id, q, q32, Points, connectivity, offsets, types
    ASSERT_EQ(ours.size(), vtks.size()) << n;
    std::uint64_t blocks = 0;
    for (std::size_t i = 0; i < ours.size(); ++i) {
      EXPECT_EQ(ours[i].blocks, vtks[i].blocks) << n << " points, array " << i;
      EXPECT_EQ(ours[i].block_size, vtks[i].block_size) << n << " points, array " << i;
      EXPECT_EQ(ours[i].last_size, vtks[i].last_size) << n << " points, array " << i;
      EXPECT_TRUE(ours[i].bytes == vtks[i].bytes) << n << " points, array " << i;
      blocks += ours[i].blocks;
    }
    EXPECT_GT(blocks, 12u) << n;  // many blocks, compressed on both threads
    expect_same_mesh(path, m);
  }
}

// Array names are XML attribute values: written escaped, read back as given.
TEST(Vtu, ArrayNamesWithXmlCharactersReadBackAsGiven) {
  TetMesh m = small_mesh();
  m.cell_data[0].name = "a<b & \"c\" 'd'>";
  const std::string path = scratch(".vtu");
  write_vtu(m, path);
  expect_same_mesh(path, m);
}

TEST(Vtu, EmptyMesh) {
  const std::string path = scratch(".vtu");
  write_vtu(TetMesh{}, path);
  expect_same_mesh(path, TetMesh{});
}

TEST(Vtu, FileIsBinaryZlibWith64BitHeaders) {
  const std::string path = scratch(".vtu");
  write_vtu(small_mesh(), path);
  const std::string text = slurp(path);
  const std::string head = text.substr(0, text.find("<Piece"));
  EXPECT_NE(head.find("compressor=\"vtkZLibDataCompressor\""), std::string::npos) << head;
  EXPECT_NE(head.find("header_type=\"UInt64\""), std::string::npos) << head;
  EXPECT_TRUE(text.find("format=\"binary\"") != std::string::npos ||
              text.find("format=\"appended\"") != std::string::npos);
  EXPECT_EQ(text.find("format=\"ascii\""), std::string::npos);
}

TEST(Vtu, MissingDirectoryThrowsOutputErrorAndLeavesNothing) {
  const std::string dir = scratch(".d");  // never created
  const std::string path = dir + "/mesh.vtu";
  try {
    write_vtu(small_mesh(), path);
    ADD_FAILURE() << "no OutputError";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_EQ(e.code(), ExitCode::output);
  }
  EXPECT_FALSE(fs::exists(dir));
}

TEST(Vtu, FailedWriteKeepsExistingFileAndLeavesNoTemp) {
  const std::string path = scratch(".vtu");
  std::ofstream(path) << "previous content";
  // A file-size limit makes the write fail part-way (as a full disk would), even for root.
  const TetMesh m = random_mesh(20000, 5);
  rlimit old{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  rlimit small = old;
  small.rlim_cur = 64 * 1024;
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  bool threw = false;
  std::string what;
  try {
    write_vtu(m, path);
  } catch (const OutputError& e) {
    threw = true;
    what = e.what();
  }
  ::setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_TRUE(threw);
  EXPECT_NE(what.find(path), std::string::npos) << what;
  EXPECT_EQ(slurp(path), "previous content");
  EXPECT_TRUE(leftover_temps(path).empty());
}

TEST(Vtu, ArraySizeMismatchIsUsageError) {
  const std::string path = scratch(".vtu");
  std::ofstream(path) << "previous content";
  auto expect_usage = [&](const TetMesh& m, const std::string& needle) {
    try {
      write_vtu(m, path);
      ADD_FAILURE() << "no UsageError";
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    EXPECT_EQ(slurp(path), "previous content");
    EXPECT_TRUE(leftover_temps(path).empty());
  };
  TetMesh m = small_mesh();
  m.point_data[1].reals.pop_back();
  expect_usage(m, "'height'");
  m = small_mesh();
  m.cell_data[0].ints.push_back(3);
  expect_usage(m, "'region'");
  m = small_mesh();
  m.tets[6] = 5;  // only points 0..4 exist
  expect_usage(m, "references point 5");
}

}  // namespace
}  // namespace kdmesh
