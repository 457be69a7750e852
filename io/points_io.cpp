// SPDX-License-Identifier: AGPL-3.0-or-later
// Point-set readers (.xyz, TetGen .node, PLY) and the .xyz writer.
//
// Every reader loads the whole file into memory and parses it in place with std::from_chars
// (exact, locale independent, no per-line allocation). Errors are InputError(file, line, what):
// the 1-based line for text data, 0 with a record index for binary data.
#include "io/points_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cerrno>
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

namespace kdmesh {

namespace {

// ---------------------------------------------------------------------------------------------
// Whole-file input and line / token scanning
// ---------------------------------------------------------------------------------------------

/// Closes a file descriptor on scope exit.
struct FdGuard {
  int fd;
  ~FdGuard() {
    if (fd >= 0) ::close(fd);
  }
};

/// The complete contents of `path`. Throws InputError (with strerror) if it cannot be read.
std::string read_whole_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  FdGuard guard{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    throw InputError(path, 0, std::string("cannot stat: ") + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) throw InputError(path, 0, "cannot read: is a directory");

  // Regular files: one buffer of the right size (+1 so the final read sees EOF without growing).
  // Pipes and other special files report no size: grow geometrically.
  std::string data(S_ISREG(st.st_mode) ? std::size_t(st.st_size) + 1 : std::size_t(1) << 16, '\0');
  std::size_t used = 0;
  for (;;) {
    if (used == data.size()) data.resize(2 * data.size());
    const ssize_t n = ::read(fd, data.data() + used, data.size() - used);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputError(path, 0, std::string("cannot read: ") + std::strerror(errno));
    }
    if (n == 0) break;
    used += std::size_t(n);
  }
  data.resize(used);
  return data;
}

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

/// Same, into a reusable vector (cleared first; keeps its capacity across calls).
void split(std::string_view s, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && is_blank(s[i])) ++i;
    if (i == s.size()) break;
    const std::size_t start = i;
    while (i < s.size() && !is_blank(s[i])) ++i;
    out.push_back(s.substr(start, i - start));
  }
}

/// A token quoted for an error message, shortened if long.
std::string quote_token(std::string_view tok) {
  constexpr std::size_t kMax = 40;
  if (tok.size() > kMax) return "'" + std::string(tok.substr(0, kMax)) + "...'";
  return "'" + std::string(tok) + "'";
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

/// Parses a whole token as an integer of type T; false if it is not one or does not fit.
template <class T>
bool parse_integer(std::string_view tok, T& value) {
  if (tok.size() > 1 && tok[0] == '+' && tok[1] != '-') tok.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), value);
  return ec == std::errc() && ptr == tok.data() + tok.size();
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

enum class PlyType : std::uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };

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

enum class PlyFormat { ascii, binary_le, binary_be };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::f32;  ///< scalar type, or the item type of a list
  bool is_list = false;
  PlyType count_type = PlyType::u8;  ///< lists only
  int coord = -1;                    ///< 0/1/2 for x/y/z of `vertex`, else -1
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::uint64_t line = 0;  ///< header line declaring it
  std::vector<PlyProperty> props;

  /// Fewest bytes a binary record can take (lists counted as empty).
  std::size_t min_binary_size() const {
    std::size_t s = 0;
    for (const PlyProperty& p : props) s += ply_size(p.is_list ? p.count_type : p.type);
    return s;
  }
};

struct PlyHeader {
  PlyFormat format = PlyFormat::ascii;
  std::vector<PlyElement> elements;
  std::size_t data_offset = 0;        ///< first byte after "end_header\n"
  std::uint64_t data_first_line = 0;  ///< line number of the first data line (ascii)
};

PlyHeader parse_ply_header(const std::string& path, std::string_view data) {
  LineCursor lines(data, /*strip_comments=*/false);
  std::string_view line;
  if (!lines.next(line) || line != "ply")
    throw InputError(path, 1, "not a PLY file: the first line must be 'ply'");

  PlyHeader h;
  bool have_format = false;
  std::vector<std::string_view> tok;
  for (;;) {
    if (!lines.next(line)) throw InputError(path, 0, "PLY header has no 'end_header' line");
    const std::uint64_t ln = lines.line();
    split(line, tok);
    if (tok.empty()) continue;
    const std::string_view key = tok[0];
    auto bad = [&](const std::string& what) {
      return InputError(path, ln, "bad PLY header line " + quote_token(line) + ": " + what);
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
        throw bad("unknown format " + quote_token(tok[1]));
      if (tok[2] != "1.0")
        throw bad("unsupported PLY version " + quote_token(tok[2]) + " (only 1.0)");
      have_format = true;
    } else if (key == "element") {
      PlyElement e;
      if (tok.size() != 3 || !parse_integer(tok[2], e.count))
        throw bad("expected 'element <name> <count>' with a non-negative count");
      e.name = tok[1];
      e.line = ln;
      h.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (h.elements.empty()) throw bad("property declared before any element");
      PlyProperty p;
      if (tok.size() == 5 && tok[1] == "list") {
        p.is_list = true;
        if (!parse_ply_type(tok[2], p.count_type) || !ply_is_integer(p.count_type))
          throw bad("list count type " + quote_token(tok[2]) + " is not an integer type");
        if (!parse_ply_type(tok[3], p.type)) throw bad("unknown type " + quote_token(tok[3]));
        p.name = tok[4];
      } else if (tok.size() == 3) {
        if (!parse_ply_type(tok[1], p.type)) throw bad("unknown type " + quote_token(tok[1]));
        p.name = tok[2];
      } else {
        throw bad("expected 'property <type> <name>' or 'property list <type> <type> <name>'");
      }
      PlyElement& e = h.elements.back();
      for (const PlyProperty& q : e.props)
        if (q.name == p.name) throw bad("duplicate property " + quote_token(p.name));
      if (e.name == "vertex" && p.name.size() == 1 && p.name[0] >= 'x' && p.name[0] <= 'z') {
        if (p.is_list) throw bad("vertex coordinate " + quote_token(p.name) + " must be a scalar");
        p.coord = p.name[0] - 'x';
      }
      e.props.push_back(std::move(p));
    } else {
      throw bad("unknown keyword " + quote_token(key));
    }
  }
  if (!have_format) throw InputError(path, 0, "PLY header has no 'format' line");
  h.data_offset = data.size() - lines.remaining();
  h.data_first_line = lines.line() + 1;
  return h;
}

/// Loads a scalar of type T stored in the file's byte order.
template <class T>
T load(const unsigned char* p, bool swap) {
  if constexpr (sizeof(T) == 1) {
    return std::bit_cast<T>(*p);
  } else {
    using U = std::conditional_t<sizeof(T) == 2, std::uint16_t,
                                 std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>;
    U u;
    std::memcpy(&u, p, sizeof u);
    if (swap) {
      if constexpr (sizeof(T) == 2)
        u = __builtin_bswap16(u);
      else if constexpr (sizeof(T) == 4)
        u = __builtin_bswap32(u);
      else
        u = __builtin_bswap64(u);
    }
    return std::bit_cast<T>(u);
  }
}

double load_as_double(const unsigned char* p, PlyType t, bool swap) {
  switch (t) {
    case PlyType::i8:
      return load<std::int8_t>(p, swap);
    case PlyType::u8:
      return load<std::uint8_t>(p, swap);
    case PlyType::i16:
      return load<std::int16_t>(p, swap);
    case PlyType::u16:
      return load<std::uint16_t>(p, swap);
    case PlyType::i32:
      return load<std::int32_t>(p, swap);
    case PlyType::u32:
      return load<std::uint32_t>(p, swap);
    case PlyType::f32:
      return load<float>(p, swap);
    case PlyType::f64:
      return load<double>(p, swap);
  }
  return 0;
}

/// A list length read from the file; negative lengths (signed count types) are returned as -1.
std::int64_t load_count(const unsigned char* p, PlyType t, bool swap) {
  switch (t) {
    case PlyType::i8:
      return std::max<std::int64_t>(-1, load<std::int8_t>(p, swap));
    case PlyType::u8:
      return load<std::uint8_t>(p, swap);
    case PlyType::i16:
      return std::max<std::int64_t>(-1, load<std::int16_t>(p, swap));
    case PlyType::u16:
      return load<std::uint16_t>(p, swap);
    case PlyType::i32:
      return std::max<std::int64_t>(-1, load<std::int32_t>(p, swap));
    case PlyType::u32:
      return load<std::uint32_t>(p, swap);
    default:
      return -1;  // floating count types are rejected by the header parser
  }
}

/// Reads (element is `vertex`: into `out`) or skips one binary element starting at `p`;
/// returns the first byte after it.
const unsigned char* walk_binary_element(const std::string& path, const PlyElement& e,
                                         const unsigned char* p, const unsigned char* end,
                                         bool swap, PointSet* out) {
  const std::size_t min_size = e.min_binary_size();
  if (min_size > 0 && e.count > std::uint64_t(end - p) / min_size)
    throw InputError(path, e.line,
                     "element '" + e.name + "' declares " + std::to_string(e.count) +
                         " records of at least " + std::to_string(min_size) + " bytes, but only " +
                         std::to_string(end - p) +
                         " bytes of data remain (truncated or corrupt file)");
  if (out) out->xyz.resize(3 * e.count);

  auto truncated = [&](std::uint64_t i) {
    return InputError(path, 0,
                      "truncated data: element '" + e.name + "' record " + std::to_string(i) +
                          " (0-based) of " + std::to_string(e.count) +
                          " runs past the end of the file");
  };
  for (std::uint64_t i = 0; i < e.count; ++i) {
    for (const PlyProperty& prop : e.props) {
      if (!prop.is_list) {
        const std::size_t size = ply_size(prop.type);
        if (std::size_t(end - p) < size) throw truncated(i);
        if (out && prop.coord >= 0) {
          const double v = load_as_double(p, prop.type, swap);
          if (!std::isfinite(v))
            throw InputError(path, 0,
                             "non-finite coordinate " + prop.name + " of vertex " +
                                 std::to_string(i) + " (0-based)");
          out->xyz[3 * i + std::size_t(prop.coord)] = v;
        }
        p += size;
      } else {
        const std::size_t count_size = ply_size(prop.count_type);
        if (std::size_t(end - p) < count_size) throw truncated(i);
        const std::int64_t n = load_count(p, prop.count_type, swap);
        if (n < 0)
          throw InputError(path, 0,
                           "negative list length in property '" + prop.name + "' of element '" +
                               e.name + "' record " + std::to_string(i) + " (0-based)");
        p += count_size;
        if (std::uint64_t(n) > std::size_t(end - p) / ply_size(prop.type)) throw truncated(i);
        p += std::size_t(n) * ply_size(prop.type);
      }
    }
  }
  return p;
}

/// Reads (element is `vertex`: into `out`) or skips one ascii element, one record per line.
void walk_ascii_element(const std::string& path, const PlyElement& e, LineCursor& lines,
                        std::vector<std::string_view>& tok, PointSet* out) {
  // Every property takes at least one character plus a separator.
  const std::uint64_t min_size = 2 * e.props.size();
  if (min_size > 0 && e.count > (lines.remaining() + 1) / min_size)
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
    split(line, tok);
    std::size_t k = 0;  // next token
    auto too_few = [&] {
      return InputError(path, ln,
                        "element '" + e.name + "' record " + std::to_string(i) +
                            " (0-based): too few values on the line");
    };
    for (const PlyProperty& prop : e.props) {
      if (k == tok.size()) throw too_few();
      if (!prop.is_list) {
        if (out && prop.coord >= 0) {
          double v;
          if (!parse_coordinate(tok[k], v, why))
            throw InputError(path, ln, "vertex " + std::to_string(i) + " (0-based): " + why);
          out->xyz[3 * i + std::size_t(prop.coord)] = v;
        }
        ++k;
      } else {
        std::uint64_t n;
        if (!parse_integer(tok[k], n))
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
  if (split(line, h) != 4 || !parse_integer(h[0], count) || !parse_integer(h[1], dim) ||
      !parse_integer(h[2], nattr) || !parse_integer(h[3], nmark))
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
    if (!parse_integer(tok[0], index))
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
                     [c](const PlyProperty& p) { return p.coord == c; }))
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
    const bool file_le = h.format == PlyFormat::binary_le;
    const bool swap = file_le != (std::endian::native == std::endian::little);
    const auto* p = reinterpret_cast<const unsigned char*>(data.data()) + h.data_offset;
    const auto* end = reinterpret_cast<const unsigned char*>(data.data()) + data.size();
    for (auto e = h.elements.begin(); e != vertex; ++e)
      p = walk_binary_element(path, *e, p, end, swap, nullptr);
    walk_binary_element(path, *vertex, p, end, swap, &out);
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
  const int fd = ::open(file.temp_path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) throw OutputError(path, std::string("cannot create: ") + std::strerror(errno));
  FdGuard guard{fd};

  auto write_all = [&](const char* p, std::size_t n) {
    while (n > 0) {
      const ssize_t w = ::write(fd, p, n);
      if (w < 0) {
        if (errno == EINTR) continue;
        throw OutputError(path, std::string("write failed: ") + std::strerror(errno));
      }
      p += w;
      n -= std::size_t(w);
    }
  };

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
  guard.fd = -1;
  if (::close(fd) != 0)
    throw OutputError(path, std::string("close failed: ") + std::strerror(errno));
  file.commit();
}

}  // namespace kdmesh
