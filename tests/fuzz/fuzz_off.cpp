// kdmesh fuzzing — read_off (io/surface_io.h) on arbitrary bytes.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/surface_io.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return kdmesh::fuzz::run_on_file(data, size, ".off",
                                   [](const std::string& p) { kdmesh::read_off(p); });
}
