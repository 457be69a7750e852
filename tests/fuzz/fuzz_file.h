// kdmesh fuzzing — shared harness: hand the fuzzer's bytes to a file reader.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Readers take paths (they must also detect formats by extension and report the file name),
// so each input is written to a per-process scratch file first. A reader may reject input
// only with a kdmesh::Error (InputError, GeometryError, ...): any other exception, a crash, a
// sanitizer report, a hang (-timeout) or a large allocation (-malloc_limit_mb) is a finding.
#pragma once
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "core/error.h"

namespace kdmesh::fuzz {

inline std::string scratch_file(const char* ext) {
  const char* dir = std::getenv("KDMESH_FUZZ_TMP");
  return std::string(dir ? dir : "/tmp") + "/kdmesh-fuzz-" + std::to_string(getpid()) + ext;
}

/// Writes the bytes to a scratch file with extension `ext` and runs `read(path)`.
template <class Reader>
int run_on_file(const std::uint8_t* data, std::size_t size, const char* ext, Reader read) {
  static const std::string path = scratch_file(ext);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  try {
    read(path);
  } catch (const kdmesh::Error&) {
    // A clear, typed rejection: the expected outcome for malformed input.
  } catch (const std::exception& e) {
    std::fprintf(stderr, "untyped exception escaped the reader: %s\n", e.what());
    std::abort();
  }
  return 0;
}

}  // namespace kdmesh::fuzz
