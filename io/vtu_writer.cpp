// SPDX-License-Identifier: AGPL-3.0-or-later
// VTU writer: the VTK XML unstructured-grid format written directly, with its binary arrays
// as raw appended data, zlib-compressed in independent 32 KiB blocks on all cores.
//
// Until 2026-11 this went through VTK's vtkXMLUnstructuredGridWriter, which compresses its
// blocks one after another on one thread: 0.42 s of pinion.ply's 0.47 s VTU write (1.08M tets),
// and most of the paper gear box's 16.8 s write, ran on one core of two. The format is the
// one VTK writes with header_type UInt64 and the zlib compressor (each array: a header of
// UInt64 [blocks, block size, size of a partial last block or 0, compressed size of each
// block], then the blocks, each one zlib stream), so VTK's, ParaView's and meshio's readers
// read it as they read VTK's own files. tests/test_io_vtu.cpp reads it back with VTK's reader.
//
// The zlib streams are made by libdeflate (a whole-buffer DEFLATE compressor), which compresses
// a block of the mesh's arrays 2.3x as fast as zlib at the same level and as small; only the
// cells' offsets and types, regular sequences that zlib's match finder packs better, go
// through zlib (see kZlibLevel). Any zlib reader decodes both.
#include "io/vtu_writer.h"

#include <libdeflate.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/parallel_for.h"
#include "io/file_io.h"
#include "io/xml_escape.h"

namespace kdmesh {

namespace {

/// Level 1, for libdeflate and zlib alike. Measured with zlib on a 6M-tet, 1M-point mesh: level
/// 1 writes in ~2 s (74 MB), level 5 (VTK's default) in ~7.5 s (72 MB), level 9 in ~90 s (71
/// MB): higher levels buy ~3%. The paper gear box's arrays (23.6M tets, 1.12 GB raw), one
/// core: zlib 10.99 s for 513.2 MB; libdeflate 4.81 s for 540.4 MB, of which its offsets 60.0
/// MB where zlib made 27.4 MB (libdeflate levels 2-6 made 55-58 MB). So libdeflate compresses
/// every array but the cells' offsets and types (ArrayCodec::zlib): 4.92 s for 507.8 MB.
constexpr int kZlibLevel = 1;
/// Uncompressed bytes per block: VTK's default, a multiple of every element size written.
constexpr std::size_t kBlock = 32768;
constexpr std::uint8_t kVtkTetra = 10;
// The arrays' bytes are written as they lie in memory, under byte_order="LittleEndian".
static_assert(std::endian::native == std::endian::little, "write_vtu writes native bytes as little-endian");

/// Which library makes an array's zlib streams (kZlibLevel says why both).
enum class ArrayCodec { libdeflate, zlib };

/// One appended array: its XML attributes and its raw little-endian bytes, either in memory
/// (`data`) or made block by block (`make(first_byte, bytes, out)`).
struct AppendedArray {
  std::string attributes;  ///< type, Name, NumberOfComponents, RangeMin/RangeMax
  std::size_t bytes = 0;
  const unsigned char* data = nullptr;
  std::function<void(std::size_t, std::size_t, unsigned char*)> make;
  ArrayCodec codec = ArrayCodec::libdeflate;
};

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

/// ' RangeMin="lo" RangeMax="hi"'.
std::string range(double lo, double hi) {
  return " RangeMin=\"" + number(lo) + "\" RangeMax=\"" + number(hi) + "\"";
}

/// The range of `n` values (none for an empty array).
template <class T>
std::string range_of(const T* v, std::size_t n) {
  if (n == 0) return "";
  const auto [lo, hi] = std::minmax_element(v, v + n);
  return range(double(*lo), double(*hi));
}

std::string attributes(const char* type, const std::string& name, int components,
                       const std::string& range_attr) {
  std::string a = "type=\"" + std::string(type) + "\" Name=\"" + xml_escape(name) + "\"";
  if (components > 1) a += " NumberOfComponents=\"" + std::to_string(components) + "\"";
  return a + range_attr;
}

template <class T>
AppendedArray in_memory(const char* type, const std::string& name, int components,
                        const std::vector<T>& v, const std::string& range) {
  return {attributes(type, name, components, range), v.size() * sizeof(T),
          reinterpret_cast<const unsigned char*>(v.data()), {}, ArrayCodec::libdeflate};
}

/// A data array of `mesh` (Float64 if it has reals, else Float32 if it has floats, else Int32),
/// checked to have `expected` entries; `kind` ("point" / "cell") names the association in errors.
AppendedArray data_array(const DataArray& a, std::size_t expected, const char* kind) {
  const std::size_t n = !a.reals.empty() ? a.reals.size() : !a.floats.empty() ? a.floats.size() : a.ints.size();
  if (n != expected)
    throw UsageError("write_vtu: " + std::string(kind) + " data array '" + a.name + "' has " +
                     std::to_string(n) + " values, expected " + std::to_string(expected) +
                     " (one per " + kind + ")");
  if (!a.reals.empty()) return in_memory("Float64", a.name, 1, a.reals, range_of(a.reals.data(), n));
  if (!a.floats.empty()) return in_memory("Float32", a.name, 1, a.floats, range_of(a.floats.data(), n));
  return in_memory("Int32", a.name, 1, a.ints, range_of(a.ints.data(), n));
}

/// Values v(i) of type T for i in [0, n), made block by block, compressed by `codec`.
template <class T, class F>
AppendedArray generated(const char* type, const char* name, std::size_t n, F v,
                        ArrayCodec codec = ArrayCodec::libdeflate) {
  AppendedArray a{attributes(type, name, 1, ""), n * sizeof(T), nullptr, {}, codec};
  a.make = [v](std::size_t first, std::size_t bytes, unsigned char* out) {
    const std::size_t i0 = first / sizeof(T);
    for (std::size_t k = 0; k < bytes / sizeof(T); ++k) {
      const T x = T(v(i0 + k));
      std::memcpy(out + k * sizeof(T), &x, sizeof(T));
    }
  };
  return a;
}

/// Every array of the file, in the order of the XML: point data, cell data, points, cells.
std::vector<AppendedArray> arrays_of(const TetMesh& mesh) {
  const std::size_t np = mesh.points.size(), nt = mesh.num_tets();
  if (mesh.tets.size() % 4 != 0)
    throw UsageError("write_vtu: tets array length " + std::to_string(mesh.tets.size()) +
                     " is not a multiple of 4");
  if (const auto bad = std::find_if(mesh.tets.begin(), mesh.tets.end(),
                                    [np](std::uint32_t v) { return v >= np; });
      bad != mesh.tets.end())
    throw UsageError("write_vtu: tet " + std::to_string((bad - mesh.tets.begin()) / 4) +
                     " references point " + std::to_string(*bad) + ", but the mesh has " +
                     std::to_string(np) + " points");
  std::vector<AppendedArray> out;
  for (const DataArray& a : mesh.point_data) out.push_back(data_array(a, np, "point"));
  for (const DataArray& a : mesh.cell_data) out.push_back(data_array(a, nt, "cell"));

  // Points: VTK's range of a vector array is that of its lengths.
  double lo = INFINITY, hi = -INFINITY;
  for (std::size_t i = 0; i < np; ++i) {
    const double* p = mesh.points.p(std::uint32_t(i));
    const double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    lo = std::min(lo, len), hi = std::max(hi, len);
  }
  const std::string points_range = np ? range(lo, hi) : "";
  out.push_back(in_memory("Float64", "Points", 3, mesh.points.xyz, points_range));

  // Cells: connectivity, the end offset of each cell, and the cell types. Int32 while every
  // offset (4 x tets) and point id fits, else Int64 (readers take both; Int32 halves what is
  // compressed: pinion.ply's connectivity + offsets 7.9 -> 7.0 MB).
  const bool int32 = 4 * nt < (std::size_t(1) << 31) && np < (std::size_t(1) << 31);
  const std::uint32_t* tets = mesh.tets.data();
  if (int32)  // point ids below 2^31: the uint32 ids are their own Int32 bytes
    out.push_back(in_memory("Int32", "connectivity", 1, mesh.tets, ""));
  else
    out.push_back(generated<std::int64_t>("Int64", "connectivity", 4 * nt,
                                          [tets](std::size_t i) { return tets[i]; }));
  const auto end_offset = [](std::size_t t) { return 4 * (t + 1); };
  if (int32)
    out.push_back(generated<std::int32_t>("Int32", "offsets", nt, end_offset, ArrayCodec::zlib));
  else
    out.push_back(generated<std::int64_t>("Int64", "offsets", nt, end_offset, ArrayCodec::zlib));
  out.push_back(generated<std::uint8_t>("UInt8", "types", nt, [](std::size_t) { return kVtkTetra; },
                                        ArrayCodec::zlib));
  return out;
}

/// One thread's compression state: a libdeflate compressor and scratch for a raw and a packed
/// block. Throws OutputError naming `path` if it cannot be allocated.
class BlockCompressor {
 public:
  explicit BlockCompressor(const std::string& path) : path_(path), raw_(kBlock) {
    deflater_ = libdeflate_alloc_compressor(kZlibLevel);
    if (!deflater_) throw OutputError(path, "out of memory for the VTU's compressor");
    packed_.resize(std::max<std::size_t>(compressBound(kBlock),
                                         libdeflate_zlib_compress_bound(deflater_, kBlock)));
  }
  ~BlockCompressor() { libdeflate_free_compressor(deflater_); }
  BlockCompressor(const BlockCompressor&) = delete;
  BlockCompressor& operator=(const BlockCompressor&) = delete;

  /// Block `b` of `a` as one zlib stream. Throws OutputError if zlib fails (out of memory).
  std::string block(const AppendedArray& a, std::size_t b) {
    const std::size_t first = b * kBlock, n = std::min(kBlock, a.bytes - first);
    const unsigned char* src = a.data ? a.data + first : raw_.data();
    if (!a.data) a.make(first, n, raw_.data());
    std::size_t len = 0;
    if (a.codec == ArrayCodec::libdeflate) {
      // The bound holds any input of n bytes: 0 (no room) cannot happen.
      len = libdeflate_zlib_compress(deflater_, src, n, packed_.data(), packed_.size());
      if (len == 0) throw OutputError(path_, "libdeflate could not compress the mesh (internal error)");
    } else {
      uLongf zlen = uLongf(packed_.size());
      if (const int rc = compress2(packed_.data(), &zlen, src, uLong(n), kZlibLevel); rc != Z_OK)
        throw OutputError(path_, std::string("zlib could not compress the mesh: ") + zError(rc));
      len = zlen;
    }
    return std::string(reinterpret_cast<const char*>(packed_.data()), len);
  }

 private:
  const std::string& path_;
  std::vector<unsigned char> raw_, packed_;
  libdeflate_compressor* deflater_ = nullptr;
};

void put_u64(std::string& s, std::uint64_t v) {
  unsigned char b[8];
  for (int k = 0; k < 8; ++k) b[k] = static_cast<unsigned char>(v >> (8 * k));
  s.append(reinterpret_cast<const char*>(b), 8);
}

}  // namespace

void write_vtu(const TetMesh& mesh, const std::string& path) {
  // Every check first: a size mismatch fails before any file is made or large work is done.
  const std::vector<AppendedArray> arrays = arrays_of(mesh);
  check_output_target(path);

  // All blocks of all arrays, compressed on all cores. The threads take runs of kRun blocks in
  // turn: the arrays' blocks differ in cost (libdeflate or zlib; compressible or not), so that
  // equal shares of the blocks are not equal shares of the work.
  std::vector<std::size_t> first_block{0};
  for (const AppendedArray& a : arrays) first_block.push_back(first_block.back() + (a.bytes + kBlock - 1) / kBlock);
  std::vector<std::string> blocks(first_block.back());
  constexpr std::size_t kRun = 16;
  const std::size_t runs = (blocks.size() + kRun - 1) / kRun;
  std::atomic<std::size_t> next_run{0};
  parallel_for(runs, [&](std::size_t, std::size_t, unsigned) {
    BlockCompressor compressor(path);
    for (std::size_t r; (r = next_run.fetch_add(1, std::memory_order_relaxed)) < runs;) {
      const std::size_t begin = r * kRun, end = std::min(blocks.size(), begin + kRun);
      std::size_t a = std::upper_bound(first_block.begin(), first_block.end(), begin) - first_block.begin() - 1;
      for (std::size_t g = begin; g < end; ++g) {
        while (g >= first_block[a + 1]) ++a;
        blocks[g] = compressor.block(arrays[a], g - first_block[a]);
      }
    }
  }, 1);

  // Each array's header, and its offset in the appended data.
  std::vector<std::string> headers(arrays.size());
  std::vector<std::uint64_t> offset(arrays.size() + 1, 0);
  for (std::size_t i = 0; i < arrays.size(); ++i) {
    const std::size_t nb = first_block[i + 1] - first_block[i];
    put_u64(headers[i], nb);
    put_u64(headers[i], kBlock);
    put_u64(headers[i], arrays[i].bytes % kBlock);
    std::uint64_t body = 0;
    for (std::size_t b = first_block[i]; b < first_block[i + 1]; ++b) {
      put_u64(headers[i], blocks[b].size());
      body += blocks[b].size();
    }
    offset[i + 1] = offset[i] + headers[i].size() + body;
  }

  const std::size_t npd = mesh.point_data.size(), ncd = mesh.cell_data.size();
  std::string xml =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">\n"
      "  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"" + std::to_string(mesh.points.size()) +
      "\" NumberOfCells=\"" + std::to_string(mesh.num_tets()) + "\">\n";
  const auto section = [&](const char* tag, std::size_t from, std::size_t to) {
    xml += std::string("      <") + tag + ">\n";
    for (std::size_t i = from; i < to; ++i)
      xml += "        <DataArray " + arrays[i].attributes + " format=\"appended\" offset=\"" +
             std::to_string(offset[i]) + "\"/>\n";
    xml += std::string("      </") + tag + ">\n";
  };
  section("PointData", 0, npd);
  section("CellData", npd, npd + ncd);
  section("Points", npd + ncd, npd + ncd + 1);
  section("Cells", npd + ncd + 1, arrays.size());
  xml += "    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";
  const char* tail = "\n  </AppendedData>\n</VTKFile>\n";

  // Written in pieces of ~1 MiB (not a syscall per 32 KiB block), each block freed once copied.
  AtomicFile file(path);
  FileWriter out(file.temp_path(), path);
  std::string pending = std::move(xml);
  const auto put = [&](std::string& piece) {
    pending += piece;
    std::string().swap(piece);
    if (pending.size() >= (std::size_t(1) << 20)) {
      out.write(pending.data(), pending.size());
      pending.clear();
    }
  };
  for (std::size_t i = 0; i < arrays.size(); ++i) {
    put(headers[i]);
    for (std::size_t b = first_block[i]; b < first_block[i + 1]; ++b) put(blocks[b]);
  }
  pending += tail;
  out.write(pending.data(), pending.size());
  out.close();
  file.commit();
}

}  // namespace kdmesh
