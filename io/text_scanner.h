// kdmesh — whitespace-token scanning with line numbers for the solver-format readers
// (internal to io/).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>

namespace kdmesh {

/// Reads an in-memory text as whitespace-separated tokens, keeping the 1-based line of the
/// last token for error messages. Every accessor that can fail throws InputError(path, line,
/// what was expected and what was found); nothing here can read past the text.
class TextScanner {
 public:
  TextScanner(std::string_view text, std::string path) : s_(text), path_(std::move(path)) {}

  /// Skips blanks and newlines; true if a token follows.
  bool more();
  /// The next non-blank character without consuming it ('\0' at the end of the text).
  char peek();
  /// The next token; `what` names it in the "unexpected end of file" error.
  std::string_view token(const char* what);
  /// The rest of the current line after the last token (trimmed), consuming it.
  std::string_view rest_of_line();
  /// The next token must equal `word` (exactly).
  void expect(std::string_view word);
  /// Consumes blanks and the end of the current line ("\n" or "\r\n"); where binary data
  /// follows a text line, it starts right after this.
  void end_of_line();
  /// `n` raw bytes at the scan position (binary data), consumed; InputError if fewer remain.
  const char* take(std::size_t n, const char* what);
  /// Moves past the next occurrence of `needle` (counting lines); false if there is none.
  bool skip_past(std::string_view needle);

  /// The next token as an integer of type T (a leading '+' allowed), or InputError naming `what`.
  std::int64_t int64(const char* what);
  std::uint64_t uint64(const char* what);
  /// A non-negative count that cannot exceed `max` (typically remaining() / bytes per item),
  /// so that a lying count is rejected before anything is allocated from it.
  std::uint64_t count(const char* what, std::uint64_t max);
  /// The next token as a finite double.
  double real(const char* what);

  std::uint64_t line() const { return line_; }
  std::size_t remaining() const { return s_.size() - pos_; }
  std::size_t position() const { return pos_; }
  const std::string& path() const { return path_; }

  /// Throws InputError(path, line(), msg).
  [[noreturn]] void fail(const std::string& msg) const;

 private:
  std::string_view s_;
  std::string path_;
  std::size_t pos_ = 0;
  std::uint64_t line_ = 1;  ///< line of the scan position (= of the last token after token())
};

/// `tok` quoted for messages ('...', at most 40 characters, unprintable bytes as '?').
std::string quoted(std::string_view tok);

}  // namespace kdmesh
