// kdmesh — line-by-line reading of line-oriented text formats (OBJ, OFF) with 1-based line
// numbers, '#' comments and CRLF line ends (internal to io/).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace kdmesh {

/// Walks a text one line at a time ("\n" or "\r\n"; a last line without a newline counts).
/// A '#' starts a comment that runs to the end of the line. Within a line, token() returns the
/// whitespace-separated tokens; nothing here can read past the text.
class TextLines {
 public:
  explicit TextLines(std::string_view text) : s_(text) {}

  /// Moves to the next line; false at the end of the text.
  bool next() {
    if (pos_ >= s_.size()) return false;
    const std::size_t nl = s_.find('\n', pos_);
    const std::size_t end = nl == std::string_view::npos ? s_.size() : nl;
    line_ = s_.substr(pos_, end - pos_);
    if (const std::size_t hash = line_.find('#'); hash != std::string_view::npos) line_ = line_.substr(0, hash);
    pos_ = end + 1;
    ++number_;
    return true;
  }

  /// Moves to the next line that holds a token (not blank, not only a comment).
  bool next_nonblank() {
    while (next())
      if (line_.find_first_not_of(kBlank) != std::string_view::npos) return true;
    return false;
  }

  /// The next token of the current line, or an empty view at its end.
  std::string_view token() {
    const std::size_t b = line_.find_first_not_of(kBlank);
    if (b == std::string_view::npos) {
      line_ = {};
      return {};
    }
    std::size_t e = line_.find_first_of(kBlank, b);
    if (e == std::string_view::npos) e = line_.size();
    const std::string_view t = line_.substr(b, e - b);
    line_.remove_prefix(e);
    return t;
  }

  /// 1-based number of the current line (0 before the first next()).
  std::uint64_t number() const { return number_; }
  /// Bytes after the current line (for checking counts against what the file can hold).
  std::size_t remaining() const { return pos_ >= s_.size() ? 0 : s_.size() - pos_; }

 private:
  static constexpr std::string_view kBlank = " \t\r\v\f";
  std::string_view s_;
  std::string_view line_;
  std::size_t pos_ = 0;
  std::uint64_t number_ = 0;
};

}  // namespace kdmesh
