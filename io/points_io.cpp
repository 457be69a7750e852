// kdmesh — point-set readers (.xyz, TetGen .node, PLY vertices) and the .xyz writer.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Point-set readers (.xyz, TetGen .node, PLY) and the .xyz writer.
//
// Every reader loads the whole file into memory and parses it in place with std::from_chars
// (exact, locale independent, no per-line allocation). Errors are InputError(file, line, what):
// the 1-based line for text data, 0 with a record index for binary data.
#include "io/points_io.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/file_io.h"
#include "io/ply_format.h"

namespace kdmesh {

namespace {

// ---------------------------------------------------------------------------------------------
// Whole-file input and line / token scanning
// ---------------------------------------------------------------------------------------------

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Walks a buffer line by line. Each line is returned without its terminator ("\n" or
/// "\r\n") and, when `strip_comments`, without anything from the first '#' on.
class LineCursor {
 public:
  LineCursor(std::string_view text, bool strip_comments, std::uint64_t first_line = 1)
      : rest_(text), strip_comments_(strip_comments), next_line_(first_line) {}

  /// The next line, or false at end of input. line() is then its 1-based number.
  bool next(std::string_view& out) {
    if (rest_.empty()) return false;
    const std::size_t nl = rest_.find('\n');
    std::string_view s = rest_.substr(0, nl);
    rest_ = nl == std::string_view::npos ? std::string_view() : rest_.substr(nl + 1);
    line_ = next_line_++;
    if (strip_comments_) {
      const std::size_t hash = s.find('#');
      if (hash != std::string_view::npos) s = s.substr(0, hash);
    }
    if (!s.empty() && s.back() == '\r') s.remove_suffix(1);
    out = s;
    return true;
  }

  /// Like next(), but skips lines that are empty or whitespace only.
  bool next_nonblank(std::string_view& out) {
    while (next(out))
      if (std::any_of(out.begin(), out.end(), [](char c) { return !is_blank(c); })) return true;
    return false;
  }

  std::uint64_t line() const { return line_; }
  /// Bytes not yet consumed.
  std::size_t remaining() const { return rest_.size(); }

 private:
  std::string_view rest_;
  bool strip_comments_;
  std::uint64_t next_line_;
  std::uint64_t line_ = 0;
};

/// Splits `s` at whitespace into out[0..N); returns the total number of tokens on the line
/// (which may exceed N: the extra ones are counted, not stored).
template <std::size_t N>
std::size_t split(std::string_view s, std::array<std::string_view, N>& out) {
  std::size_t count = 0;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && is_blank(s[i])) ++i;
    if (i == s.size()) break;
    const std::size_t start = i;
    while (i < s.size() && !is_blank(s[i])) ++i;
    if (count < N) out[count] = s.substr(start, i - start);
    ++count;
  }
  return count;
}

/// A token quoted for an error message, shortened if long.
std::string quote_token(std::string_view tok) {
  constexpr std::size_t kMax = 40;
  // Appended piece by piece: "'" + std::string(...) trips a GCC 12 -Wrestrict false positive.
  std::string s = "'";
  s.append(tok.substr(0, kMax));
  s += tok.size() > kMax ? "...'" : "'";
  return s;
}

// ---------------------------------------------------------------------------------------------
// Number parsing
// ---------------------------------------------------------------------------------------------

/// Parses a whole token as a finite double. On failure returns false and sets `why`.
/// A leading '+' is accepted (std::from_chars alone rejects it).
bool parse_coordinate(std::string_view tok, double& value, std::string& why) {
  std::string_view t = tok;
  if (t.size() > 1 && t[0] == '+' && t[1] != '-' && t[1] != '+') t.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (ec == std::errc::result_out_of_range && ptr == t.data() + t.size()) {
    why = quote_token(tok) + " is out of the range of a double";
    return false;
  }
  if (ec != std::errc() || ptr != t.data() + t.size()) {
    why = quote_token(tok) + " is not a number";
    return false;
  }
  if (!std::isfinite(value)) {
    why = "non-finite coordinate " + quote_token(tok);
    return false;
  }
  return true;
}

/// Parses x, y, z tokens and appends the point; throws InputError at `line` on failure.
void append_point(PointSet& out, const std::string& path, std::uint64_t line,
                  const std::string_view* tok) {
  double c[3];
  std::string why;
  for (int k = 0; k < 3; ++k)
    if (!parse_coordinate(tok[k], c[k], why)) throw InputError(path, line, why);
  out.push_back(c[0], c[1], c[2]);
}

// ---------------------------------------------------------------------------------------------
// PLY
// ---------------------------------------------------------------------------------------------

/// Reads (element is `vertex`: into `out`) or skips one binary element starting at `p`;
/// returns the first byte after it.
const unsigned char* walk_binary_element(const std::string& path, const PlyElement& e,
                                         const unsigned char* p, const unsigned char* end,
                                         PlyFormat format, PointSet* out) {
  if (!ply_count_fits(e, format, std::size_t(end - p)))
    throw InputError(path, e.line,
                     "element '" + e.name + "' declares " + std::to_string(e.count) +
                         " records of at least " +
                         std::to_string(ply_min_record_size(e, format)) +
                         " bytes, but only " + std::to_string(end - p) +
                         " bytes of data remain (truncated or corrupt file)");
  if (out) out->xyz.resize(3 * e.count);

  const bool swap = ply_needs_swap(format);
  for (std::uint64_t i = 0; i < e.count; ++i) {
    const PlyProperty* fault = nullptr;
    const PlyRecordEnd status = walk_ply_binary_record(
        e, p, end, swap, fault,
        [&](const PlyProperty& prop, const unsigned char* bytes) {
          if (!out || prop.role < 0) return;
          const double v = load_ply_double(bytes, prop.type, swap);
          if (!std::isfinite(v))
            throw InputError(path, 0,
                             "non-finite coordinate " + prop.name + " of vertex " +
                                 std::to_string(i) + " (0-based)");
          out->xyz[3 * i + std::size_t(prop.role)] = v;
        },
        [](const PlyProperty&, std::size_t, const unsigned char*) {});
    if (status == PlyRecordEnd::truncated)
      throw InputError(path, 0,
                       "truncated data: element '" + e.name + "' record " + std::to_string(i) +
                           " (0-based) of " + std::to_string(e.count) +
                           " runs past the end of the file");
    if (status == PlyRecordEnd::negative_list_length)
      throw InputError(path, 0,
                       "negative list length in property '" + fault->name + "' of element '" +
                           e.name + "' record " + std::to_string(i) + " (0-based)");
  }
  return p;
}

/// Reads (element is `vertex`: into `out`) or skips one ascii element, one record per line.
void walk_ascii_element(const std::string& path, const PlyElement& e, LineCursor& lines,
                        std::vector<std::string_view>& tok, PointSet* out) {
  if (!ply_count_fits(e, PlyFormat::ascii, lines.remaining()))
    throw InputError(path, e.line,
                     "element '" + e.name + "' declares " + std::to_string(e.count) +
                         " records, but only " + std::to_string(lines.remaining()) +
                         " bytes of data remain (truncated or corrupt file)");
  if (e.props.empty()) return;
  if (out) out->xyz.resize(3 * e.count);

  std::string_view line;
  std::string why;
  for (std::uint64_t i = 0; i < e.count; ++i) {
    if (!lines.next_nonblank(line))
      throw InputError(path, 0,
                       "truncated data: file ends at element '" + e.name + "' record " +
                           std::to_string(i) + " (0-based) of " + std::to_string(e.count));
    const std::uint64_t ln = lines.line();
    split_ply_line(line, tok);
    std::size_t k = 0;  // next token
    auto too_few = [&] {
      return InputError(path, ln,
                        "element '" + e.name + "' record " + std::to_string(i) +
                            " (0-based): too few values on the line");
    };
    for (const PlyProperty& prop : e.props) {
      if (k == tok.size()) throw too_few();
      if (!prop.is_list) {
        if (out && prop.role >= 0) {
          double v;
          if (!parse_coordinate(tok[k], v, why))
            throw InputError(path, ln, "vertex " + std::to_string(i) + " (0-based): " + why);
          out->xyz[3 * i + std::size_t(prop.role)] = v;
        }
        ++k;
      } else {
        std::uint64_t n;
        if (!parse_whole_token(tok[k], n))
          throw InputError(path, ln,
                           "list length " + quote_token(tok[k]) + " of property '" + prop.name +
                               "' is not a non-negative integer");
        ++k;
        if (n > tok.size() - k) throw too_few();
        k += std::size_t(n);
      }
    }
    if (k != tok.size())
      throw InputError(path, ln,
                       "element '" + e.name + "' record " + std::to_string(i) +
                           " (0-based): " + std::to_string(tok.size() - k) +
                           " value(s) more than its properties declare");
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Public readers
// ---------------------------------------------------------------------------------------------

PointSet read_points(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".xyz") return read_xyz(path);
  if (ext == ".node") return read_tetgen_node(path);
  if (ext == ".ply") return read_ply_points(path);
  throw InputError(
      path, 0,
      "unknown point file extension " + quote_token(ext) + " (supported: .xyz, .node, .ply)");
}

PointSet read_xyz(const std::string& path) {
  const std::string data = read_whole_file(path);
  PointSet out;
  // At most one point per line: count the lines once so the array never reallocates.
  out.xyz.reserve(3 * (std::size_t(std::count(data.begin(), data.end(), '\n')) + 1));
  LineCursor lines(data, /*strip_comments=*/true);
  std::array<std::string_view, 3> tok;
  std::string_view line;
  while (lines.next(line)) {
    const std::size_t n = split(line, tok);
    if (n == 0) continue;
    if (n != 3)
      throw InputError(path, lines.line(),
                       "expected 3 numbers (x y z), found " + std::to_string(n) + " fields");
    append_point(out, path, lines.line(), tok.data());
  }
  return out;
}

PointSet read_tetgen_node(const std::string& path) {
  const std::string data = read_whole_file(path);
  LineCursor lines(data, /*strip_comments=*/true);
  std::string_view line;
  PointSet out;
  if (!lines.next_nonblank(line)) return out;  // no header, no points

  // Header: <#points> <dim> <#attributes> <#boundary markers>.
  std::array<std::string_view, 4> h;
  const std::uint64_t header_line = lines.line();
  std::uint64_t count = 0, dim = 0, nattr = 0, nmark = 0;
  if (split(line, h) != 4 || !parse_whole_token(h[0], count) || !parse_whole_token(h[1], dim) ||
      !parse_whole_token(h[2], nattr) || !parse_whole_token(h[3], nmark))
    throw InputError(path, header_line,
                     "bad .node header " + quote_token(line) +
                         ": expected '<#points> <dimension> <#attributes> <#boundary markers>' "
                         "(non-negative integers)");
  if (dim != 3)
    throw InputError(path, header_line, "dimension is " + std::to_string(dim) + ", must be 3");
  if (nmark > 1)
    throw InputError(path, header_line,
                     "#boundary markers is " + std::to_string(nmark) + ", must be 0 or 1");
  if (nattr > lines.remaining())  // also keeps the field count below from overflowing
    throw InputError(path, header_line,
                     "#attributes " + std::to_string(nattr) + " exceeds the file size");
  const std::uint64_t fields = 4 + nattr + nmark;

  // Reserve no more than the data could possibly hold ("i x y z\n" is 8 bytes).
  out.xyz.reserve(3 * std::min<std::uint64_t>(count, lines.remaining() / 8 + 1));
  std::array<std::string_view, 4> tok;
  std::int64_t base = 0;
  for (std::uint64_t i = 0; i < count; ++i) {
    if (!lines.next_nonblank(line))
      throw InputError(path, 0,
                       "unexpected end of file: the header (line " + std::to_string(header_line) +
                           ") declares " + std::to_string(count) + " points, found only " +
                           std::to_string(i));
    const std::uint64_t ln = lines.line();
    const std::size_t n = split(line, tok);
    if (n != fields)
      throw InputError(path, ln,
                       "expected " + std::to_string(fields) + " fields (index x y z + " +
                           std::to_string(nattr) + " attributes + " + std::to_string(nmark) +
                           " markers), found " + std::to_string(n));
    std::int64_t index;
    if (!parse_whole_token(tok[0], index))
      throw InputError(path, ln, "point index " + quote_token(tok[0]) + " is not an integer");
    if (i == 0) {
      if (index != 0 && index != 1)
        throw InputError(path, ln,
                         "first point index is " + std::to_string(index) + ", must be 0 or 1");
      base = index;
    } else if (index != base + std::int64_t(i)) {
      throw InputError(path, ln,
                       "point index " + std::to_string(index) + " out of sequence (expected " +
                           std::to_string(base + std::int64_t(i)) + ")");
    }
    append_point(out, path, ln, tok.data() + 1);
  }
  if (lines.next_nonblank(line))
    throw InputError(path, lines.line(),
                     "unexpected data after the " + std::to_string(count) +
                         " points declared by the header (line " + std::to_string(header_line) +
                         ")");
  return out;
}

PointSet read_ply_points(const std::string& path) {
  const std::string data = read_whole_file(path);
  const PlyHeader h = parse_ply_header(path, data);

  const auto vertex = std::find_if(h.elements.begin(), h.elements.end(),
                                   [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex == h.elements.end())
    throw InputError(path, 0, "PLY header declares no 'vertex' element");
  for (int c = 0; c < 3; ++c)
    if (std::none_of(vertex->props.begin(), vertex->props.end(),
                     [c](const PlyProperty& p) { return p.role == c; }))
      throw InputError(path, vertex->line,
                       std::string("element 'vertex' has no property '") + char('x' + c) + "'");

  PointSet out;
  if (h.format == PlyFormat::ascii) {
    LineCursor lines(std::string_view(data).substr(h.data_offset), /*strip_comments=*/false,
                     h.data_first_line);
    std::vector<std::string_view> tok;
    for (auto e = h.elements.begin(); e != vertex; ++e)
      walk_ascii_element(path, *e, lines, tok, nullptr);
    walk_ascii_element(path, *vertex, lines, tok, &out);
  } else {
    const auto* p = reinterpret_cast<const unsigned char*>(data.data()) + h.data_offset;
    const auto* end = reinterpret_cast<const unsigned char*>(data.data()) + data.size();
    for (auto e = h.elements.begin(); e != vertex; ++e)
      p = walk_binary_element(path, *e, p, end, h.format, nullptr);
    walk_binary_element(path, *vertex, p, end, h.format, &out);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Writer
// ---------------------------------------------------------------------------------------------

void write_xyz(const PointSet& points, const std::string& path) {
  for (std::size_t i = 0; i < points.xyz.size(); ++i)
    if (!std::isfinite(points.xyz[i]))
      throw UsageError("write_xyz: point " + std::to_string(i / 3) +
                       " has a non-finite coordinate");

  AtomicFile file(path);
  FileWriter writer(file.temp_path(), path);
  auto write_all = [&](const char* p, std::size_t n) { writer.write(p, n); };

  // Formatted in 4 MiB chunks: as fast as a single buffer, bounded memory for huge sets.
  constexpr std::size_t kChunk = std::size_t(4) << 20;
  constexpr std::size_t kMaxPoint = 3 * 25 + 3;  // 3 doubles of <= 24 chars + separators
  std::vector<char> buf(kChunk + kMaxPoint);
  char* const begin = buf.data();
  char* out = begin;
  const std::string header = "# kdmesh points: " + std::to_string(points.size()) + "\n";
  out = std::copy(header.begin(), header.end(), out);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double* p = points.xyz.data() + 3 * i;
    for (int k = 0; k < 3; ++k) {
      out = std::to_chars(out, begin + buf.size(), p[k]).ptr;
      *out++ = k < 2 ? ' ' : '\n';
    }
    if (std::size_t(out - begin) >= kChunk) {
      write_all(begin, std::size_t(out - begin));
      out = begin;
    }
  }
  write_all(begin, std::size_t(out - begin));
  writer.close();
  file.commit();
}

}  // namespace kdmesh
