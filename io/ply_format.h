// kdmesh — PLY header parsing and binary value decoding shared by the PLY readers (internal to io/).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Used by read_ply_points (io/points_io.cpp) and read_ply (io/surface_io.cpp); not a public
// header. parse_ply_header validates the whole header and reports where the data starts; the
// readers walk the data themselves (each knows which elements it keeps), using the helpers
// below for the parts that are the same in both: value types, scalar decoding with the file's
// byte order, the plausibility of element counts against the bytes left, and the bounds-checked
// walk over one binary record.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace kdmesh {

/// The scalar types of PLY 1.0 (both the classic and the sized spellings are accepted).
enum class PlyType : std::uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };

/// Size of one value of type `t` in binary data, in bytes (1, 2, 4 or 8).
std::size_t ply_size(PlyType t);
/// True for the integer types (all but f32, f64).
bool ply_is_integer(PlyType t);

enum class PlyFormat { ascii, binary_le, binary_be };

/// Splits one line of a PLY header or of ascii PLY data into its tokens, separated by blanks
/// (space, tab, CR, VT, FF). `tokens` is cleared first and keeps its capacity across calls.
void split_ply_line(std::string_view line, std::vector<std::string_view>& tokens);

/// PlyProperty::role of the vertex index list of `face` ('vertex_indices' or 'vertex_index').
inline constexpr int kPlyFaceIndices = 3;

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::f32;       ///< scalar type, or the item type of a list
  bool is_list = false;
  PlyType count_type = PlyType::u8;  ///< lists only (always an integer type)
  /// -1, or what the property means: 0/1/2 = x/y/z of `vertex` (always scalar);
  /// kPlyFaceIndices = the vertex index list of `face` (always a list of an integer type).
  int role = -1;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;  ///< records declared by the header (not yet checked against data)
  std::uint64_t line = 0;   ///< header line declaring it (1-based)
  std::vector<PlyProperty> props;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::ascii;
  std::vector<PlyElement> elements;   ///< in file order; names are unique
  std::size_t data_offset = 0;        ///< first byte after the "end_header" line
  std::uint64_t data_first_line = 0;  ///< 1-based line number of that byte (ascii data)
};

/// Parses and validates the header at the start of `data` (the whole file). Throws
/// InputError(path, line, ...) naming the header line at fault ("bad PLY header line '...':
/// ..."), line 1 if the file does not start with "ply", and line 0 when the header has no
/// 'format' or no 'end_header' line. Lines may end in "\n" or "\r\n".
PlyHeader parse_ply_header(const std::string& path, std::string_view data);

/// Fewest bytes one record of `e` can take: in binary the sizes of its scalars and list counts
/// (lists counted as empty); in ascii one character and one separator per property.
std::size_t ply_min_record_size(const PlyElement& e, PlyFormat format);

/// False if `bytes` bytes cannot hold the e.count records `e` declares (at
/// ply_min_record_size each; in ascii the last record may lack its newline). Readers check
/// this BEFORE allocating anything from e.count, so a lying header fails fast.
bool ply_count_fits(const PlyElement& e, PlyFormat format, std::size_t bytes);

/// True if binary data in `format` must be byte-swapped on this machine.
bool ply_needs_swap(PlyFormat format);

/// The value of type `t` stored at `p` (ply_size(t) bytes, byte-swapped if `swap`), as a
/// double; exact for every type (integers of up to 32 bits fit a double).
double load_ply_double(const unsigned char* p, PlyType t, bool swap);
/// The integer of type `t` stored at `p` (index or list length); exact for every integer
/// type. Floating types (which the header parser never allows as list counts) give -1.
std::int64_t load_ply_int(const unsigned char* p, PlyType t, bool swap);

/// How walk_ply_binary_record ended.
enum class PlyRecordEnd { ok, truncated, negative_list_length };

/// Walks one binary record of `e` that starts at `p`, never reading at or past `end`. In
/// property order: a scalar calls scalar(prop, bytes) and a list calls list(prop, n, items)
/// (n items of ply_size(prop.type) bytes at `items`), each only once the bytes it covers are
/// known to lie before `end`. Returns ok with `p` past the record, or (with `fault` the
/// property at fault and `p` at it) truncated if the record runs past `end`, or
/// negative_list_length if a signed list count is negative. The callbacks may throw.
template <class Scalar, class List>
PlyRecordEnd walk_ply_binary_record(const PlyElement& e, const unsigned char*& p,
                                    const unsigned char* end, bool swap,
                                    const PlyProperty*& fault, Scalar&& scalar, List&& list) {
  for (const PlyProperty& prop : e.props) {
    fault = &prop;
    if (!prop.is_list) {
      const std::size_t size = ply_size(prop.type);
      if (std::size_t(end - p) < size) return PlyRecordEnd::truncated;
      scalar(prop, p);
      p += size;
      continue;
    }
    const std::size_t count_size = ply_size(prop.count_type);
    if (std::size_t(end - p) < count_size) return PlyRecordEnd::truncated;
    const std::int64_t n = load_ply_int(p, prop.count_type, swap);
    if (n < 0) return PlyRecordEnd::negative_list_length;
    const unsigned char* items = p + count_size;
    const std::size_t item_size = ply_size(prop.type);
    if (std::uint64_t(n) > std::size_t(end - items) / item_size) return PlyRecordEnd::truncated;
    list(prop, std::size_t(n), items);
    p = items + std::size_t(n) * item_size;
  }
  fault = nullptr;
  return PlyRecordEnd::ok;
}

}  // namespace kdmesh
