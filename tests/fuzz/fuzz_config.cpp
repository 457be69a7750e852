// kdmesh fuzzing — the YAML batch-config loader (tools/app/job_config.h) on arbitrary bytes.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "tests/fuzz/fuzz_file.h"
#include "tools/app/job_config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return kdmesh::fuzz::run_on_file(data, size, ".yaml", [](const std::string& p) {
    kdmesh::load_batch_config(p, "/tmp");
  });
}
