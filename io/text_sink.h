// kdmesh — buffered text (and raw byte) output for the solver-format writers (internal to io/).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

#include "io/file_io.h"

namespace kdmesh {

/// Appends numbers and strings into one fixed buffer and hands it to a FileWriter whenever it
/// fills: no per-line std::string, no iostream, bounded memory for any mesh size. Numbers are
/// formatted with std::to_chars (locale independent; doubles in their shortest round-trip form,
/// so a reader that parses with strtod/from_chars gets every double back bit for bit).
/// Call flush() before closing the FileWriter.
class TextSink {
 public:
  explicit TextSink(FileWriter& out, std::size_t capacity = std::size_t(4) << 20)
      : out_(out), buf_(capacity + kSlack), cur_(buf_.data()), end_(buf_.data() + capacity) {}
  TextSink(const TextSink&) = delete;
  TextSink& operator=(const TextSink&) = delete;

  TextSink& put(std::string_view s) {
    if (s.size() > kSlack) {
      flush();
      out_.write(s.data(), s.size());
      return *this;
    }
    std::memcpy(cur_, s.data(), s.size());
    cur_ += s.size();
    return maybe_drain();
  }
  TextSink& put(char c) {
    *cur_++ = c;
    return maybe_drain();
  }
  TextSink& put_uint(std::uint64_t v) {
    cur_ = std::to_chars(cur_, cur_ + 24, v).ptr;
    return maybe_drain();
  }
  TextSink& put_int(std::int64_t v) {
    cur_ = std::to_chars(cur_, cur_ + 24, v).ptr;
    return maybe_drain();
  }
  /// Shortest representation that reads back as exactly `v` (at most 24 characters).
  TextSink& put_real(double v) {
    cur_ = std::to_chars(cur_, cur_ + 32, v).ptr;
    return maybe_drain();
  }
  /// `v` in at most `max_chars` characters (>= 8): the shortest round-trip form when it fits,
  /// otherwise the most significant digits that fit (general format, so at least 12 of them
  /// for max_chars = 20). Used where a reader cuts fields to a fixed width (CalculiX: 20).
  TextSink& put_real_width(double v, int max_chars) {
    char tmp[40];
    char* e = std::to_chars(tmp, tmp + sizeof tmp, v).ptr;
    for (int prec = 17; e - tmp > max_chars && prec > 1; --prec)
      e = std::to_chars(tmp, tmp + sizeof tmp, v, std::chars_format::general, prec).ptr;
    return put(std::string_view(tmp, std::size_t(e - tmp)));
  }
  /// Raw bytes (binary formats): the object representation of `v`, native byte order.
  template <class T>
  TextSink& put_binary(const T& v) {
    static_assert(sizeof(T) <= 64);
    std::memcpy(cur_, &v, sizeof(T));
    cur_ += sizeof(T);
    return maybe_drain();
  }

  /// Writes out everything buffered.
  void flush() {
    out_.write(buf_.data(), std::size_t(cur_ - buf_.data()));
    cur_ = buf_.data();
  }

 private:
  /// Room every single put may use past end_ before the buffer is drained.
  static constexpr std::size_t kSlack = 256;

  TextSink& maybe_drain() {
    if (cur_ >= end_) flush();
    return *this;
  }

  FileWriter& out_;
  std::vector<char> buf_;
  char* cur_;
  char* end_;
};

}  // namespace kdmesh
