// kdmesh — PLY header parsing and binary value decoding shared by the PLY readers.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/ply_format.h"

#include <bit>
#include <cctype>
#include <charconv>
#include <cstring>
#include <utility>

#include "core/error.h"
#include "io/file_io.h"

namespace kdmesh {

namespace {

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

bool parse_ply_type(std::string_view s, PlyType& t) {
  struct Name {
    std::string_view name;
    PlyType type;
  };
  static constexpr Name kNames[] = {
      {"char", PlyType::i8},     {"int8", PlyType::i8},     {"uchar", PlyType::u8},
      {"uint8", PlyType::u8},    {"short", PlyType::i16},   {"int16", PlyType::i16},
      {"ushort", PlyType::u16},  {"uint16", PlyType::u16},  {"int", PlyType::i32},
      {"int32", PlyType::i32},   {"uint", PlyType::u32},    {"uint32", PlyType::u32},
      {"float", PlyType::f32},   {"float32", PlyType::f32}, {"double", PlyType::f64},
      {"float64", PlyType::f64},
  };
  for (const Name& n : kNames)
    if (n.name == s) {
      t = n.type;
      return true;
    }
  return false;
}

/// The unsigned integer of sizeof(U) bytes at `p`, byte-swapped if `swap`.
template <class U>
U load_raw(const unsigned char* p, bool swap) {
  U u;
  std::memcpy(&u, p, sizeof u);
  if (swap) {
    if constexpr (sizeof(U) == 2)
      u = __builtin_bswap16(u);
    else if constexpr (sizeof(U) == 4)
      u = __builtin_bswap32(u);
    else
      u = __builtin_bswap64(u);
  }
  return u;
}

}  // namespace

std::size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::i8:
    case PlyType::u8:
      return 1;
    case PlyType::i16:
    case PlyType::u16:
      return 2;
    case PlyType::i32:
    case PlyType::u32:
    case PlyType::f32:
      return 4;
    case PlyType::f64:
      return 8;
  }
  return 0;
}

bool ply_is_integer(PlyType t) { return t != PlyType::f32 && t != PlyType::f64; }

void split_ply_line(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_blank(line[i])) ++i;
    if (i == line.size()) break;
    const std::size_t start = i;
    while (i < line.size() && !is_blank(line[i])) ++i;
    tokens.push_back(line.substr(start, i - start));
  }
}

PlyHeader parse_ply_header(const std::string& path, std::string_view data) {
  std::size_t pos = 0;    // start of the next line
  std::uint64_t ln = 0;   // number of the current line
  // The next line without its "\n" or "\r\n"; false at end of input.
  auto next_line = [&](std::string_view& line) {
    if (pos >= data.size()) return false;
    const std::size_t nl = data.find('\n', pos);
    line = data.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    pos = nl == std::string_view::npos ? data.size() : nl + 1;
    ++ln;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return true;
  };

  std::string_view line;
  if (!next_line(line) || line != "ply")
    throw InputError(path, 1, "not a PLY file: the first line must be 'ply'");

  PlyHeader h;
  bool have_format = false;
  std::vector<std::string_view> tok;
  for (;;) {
    if (!next_line(line)) throw InputError(path, 0, "PLY header has no 'end_header' line");
    split_ply_line(line, tok);
    if (tok.empty()) continue;
    const std::string_view key = tok[0];
    auto bad = [&](const std::string& what) {
      return InputError(path, ln, "bad PLY header line " + quote_token_printable(line) + ": " + what);
    };
    if (key == "comment" || key == "obj_info") continue;
    if (key == "end_header") {
      if (tok.size() != 1) throw bad("unexpected text after 'end_header'");
      break;
    }
    if (key == "format") {
      if (have_format) throw bad("duplicate 'format' line");
      if (tok.size() != 3)
        throw bad("expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
      if (tok[1] == "ascii")
        h.format = PlyFormat::ascii;
      else if (tok[1] == "binary_little_endian")
        h.format = PlyFormat::binary_le;
      else if (tok[1] == "binary_big_endian")
        h.format = PlyFormat::binary_be;
      else
        throw bad("unknown format " + quote_token_printable(tok[1]));
      if (tok[2] != "1.0") throw bad("unsupported PLY version " + quote_token_printable(tok[2]) + " (only 1.0)");
      have_format = true;
    } else if (key == "element") {
      PlyElement e;
      if (tok.size() != 3 || !parse_whole_token(tok[2], e.count))
        throw bad("expected 'element <name> <count>' with a non-negative count");
      e.name = tok[1];
      e.line = ln;
      for (const PlyElement& o : h.elements)
        if (o.name == e.name) throw bad("duplicate element " + quote_token_printable(e.name));
      h.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (h.elements.empty()) throw bad("property declared before any element");
      PlyProperty p;
      if (tok.size() == 5 && tok[1] == "list") {
        p.is_list = true;
        if (!parse_ply_type(tok[2], p.count_type) || !ply_is_integer(p.count_type))
          throw bad("list count type " + quote_token_printable(tok[2]) + " is not an integer type");
        if (!parse_ply_type(tok[3], p.type)) throw bad("unknown type " + quote_token_printable(tok[3]));
        p.name = tok[4];
      } else if (tok.size() == 3) {
        if (!parse_ply_type(tok[1], p.type)) throw bad("unknown type " + quote_token_printable(tok[1]));
        p.name = tok[2];
      } else {
        throw bad("expected 'property <type> <name>' or 'property list <type> <type> <name>'");
      }
      PlyElement& e = h.elements.back();
      for (const PlyProperty& q : e.props)
        if (q.name == p.name) throw bad("duplicate property " + quote_token_printable(p.name));
      if (e.name == "vertex" && (p.name == "x" || p.name == "y" || p.name == "z")) {
        if (p.is_list) throw bad("vertex coordinate " + quote_token_printable(p.name) + " must be a scalar");
        p.role = p.name[0] - 'x';
      }
      if (e.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index")) {
        if (!p.is_list) throw bad("face property " + quote_token_printable(p.name) + " must be a list");
        if (!ply_is_integer(p.type)) throw bad("vertex indices must have an integer type");
        for (const PlyProperty& q : e.props)
          if (q.role == kPlyFaceIndices) throw bad("two vertex index lists in 'face'");
        p.role = kPlyFaceIndices;
      }
      e.props.push_back(std::move(p));
    } else {
      throw bad("unknown keyword " + quote_token_printable(key));
    }
  }
  if (!have_format) throw InputError(path, 0, "PLY header has no 'format' line");
  h.data_offset = pos;
  h.data_first_line = ln + 1;
  return h;
}

std::size_t ply_min_record_size(const PlyElement& e, PlyFormat format) {
  if (format == PlyFormat::ascii) return 2 * e.props.size();
  std::size_t s = 0;
  for (const PlyProperty& p : e.props) s += ply_size(p.is_list ? p.count_type : p.type);
  return s;
}

bool ply_count_fits(const PlyElement& e, PlyFormat format, std::size_t bytes) {
  const std::size_t min_size = ply_min_record_size(e, format);
  // ascii: the last record needs no separator after it (no final newline).
  const std::uint64_t room = format == PlyFormat::ascii ? std::uint64_t(bytes) + 1 : bytes;
  return min_size == 0 || e.count <= room / min_size;
}

bool ply_needs_swap(PlyFormat format) {
  return (format == PlyFormat::binary_le) != (std::endian::native == std::endian::little);
}

double load_ply_double(const unsigned char* p, PlyType t, bool swap) {
  switch (t) {
    case PlyType::i8:
      return std::int8_t(*p);
    case PlyType::u8:
      return *p;
    case PlyType::i16:
      return std::int16_t(load_raw<std::uint16_t>(p, swap));
    case PlyType::u16:
      return load_raw<std::uint16_t>(p, swap);
    case PlyType::i32:
      return std::int32_t(load_raw<std::uint32_t>(p, swap));
    case PlyType::u32:
      return load_raw<std::uint32_t>(p, swap);
    case PlyType::f32:
      return std::bit_cast<float>(load_raw<std::uint32_t>(p, swap));
    case PlyType::f64:
      return std::bit_cast<double>(load_raw<std::uint64_t>(p, swap));
  }
  return 0;
}

std::int64_t load_ply_int(const unsigned char* p, PlyType t, bool swap) {
  switch (t) {
    case PlyType::f32:
    case PlyType::f64:
      return -1;
    default:
      return std::int64_t(load_ply_double(p, t, swap));  // exact: integers of <= 32 bits
  }
}

}  // namespace kdmesh
