// kdmesh — whitespace-token scanning with line numbers for the solver-format readers.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/text_scanner.h"

#include <charconv>
#include <cmath>

#include "core/error.h"
#include "io/file_io.h"

namespace kdmesh {

namespace {

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

}  // namespace

std::string quoted(std::string_view tok) { return quote_token_printable(tok); }

bool TextScanner::more() {
  while (pos_ < s_.size() && is_space(s_[pos_])) {
    if (s_[pos_] == '\n') ++line_;
    ++pos_;
  }
  return pos_ < s_.size();
}

char TextScanner::peek() { return more() ? s_[pos_] : '\0'; }

std::string_view TextScanner::token(const char* what) {
  if (!more()) fail(std::string("unexpected end of file, expected ") + what);
  const std::size_t start = pos_;
  while (pos_ < s_.size() && !is_space(s_[pos_])) ++pos_;
  return s_.substr(start, pos_ - start);
}

std::string_view TextScanner::rest_of_line() {
  while (pos_ < s_.size() && s_[pos_] != '\n' && is_space(s_[pos_])) ++pos_;
  const std::size_t start = pos_;
  while (pos_ < s_.size() && s_[pos_] != '\n') ++pos_;
  std::size_t end = pos_;
  while (end > start && is_space(s_[end - 1])) --end;
  return s_.substr(start, end - start);
}

void TextScanner::expect(std::string_view word) {
  const std::string w(word);
  const std::string_view tok = token(w.c_str());
  if (tok != word) fail("expected " + quoted(word) + ", found " + quoted(tok));
}

void TextScanner::end_of_line() {
  while (pos_ < s_.size() && s_[pos_] != '\n' && is_space(s_[pos_])) ++pos_;
  if (pos_ == s_.size()) fail("unexpected end of file, expected the end of the line");
  if (s_[pos_] != '\n') fail("unexpected " + quoted(s_.substr(pos_, 1)) + " at the end of a line");
  ++pos_;
  ++line_;
}

const char* TextScanner::take(std::size_t n, const char* what) {
  if (n > remaining())
    fail(std::string("unexpected end of file in binary data (") + what + ": " +
         std::to_string(n) + " bytes needed, " + std::to_string(remaining()) + " left)");
  const char* p = s_.data() + pos_;
  pos_ += n;
  return p;
}

bool TextScanner::skip_past(std::string_view needle) {
  const std::size_t at = s_.find(needle, pos_);
  if (at == std::string_view::npos) return false;
  for (std::size_t i = pos_; i < at + needle.size(); ++i) line_ += s_[i] == '\n';
  pos_ = at + needle.size();
  return true;
}

std::int64_t TextScanner::int64(const char* what) {
  const std::string_view tok = token(what);
  std::int64_t v;
  if (!parse_whole_token(tok, v)) fail(std::string(what) + ": " + quoted(tok) + " is not an integer");
  return v;
}

std::uint64_t TextScanner::uint64(const char* what) {
  const std::string_view tok = token(what);
  std::uint64_t v;
  if (!parse_whole_token(tok, v))
    fail(std::string(what) + ": " + quoted(tok) + " is not a non-negative integer");
  return v;
}

std::uint64_t TextScanner::count(const char* what, std::uint64_t max) {
  const std::uint64_t n = uint64(what);
  if (n > max)
    fail(std::string(what) + " " + std::to_string(n) + " exceeds what the remaining " +
         std::to_string(remaining()) + " bytes of the file can hold (truncated or corrupt file)");
  return n;
}

double TextScanner::real(const char* what) {
  const std::string_view tok = token(what);
  double v;
  if (!parse_whole_token(tok, v)) fail(std::string(what) + ": " + quoted(tok) + " is not a number");
  if (!std::isfinite(v)) fail(std::string(what) + ": non-finite value " + quoted(tok));
  return v;
}

void TextScanner::fail(const std::string& msg) const { throw InputError(path_, line_, msg); }

}  // namespace kdmesh
