// PageWarmer: pages become resident, contents never change, stop() is prompt.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <thread>
#include <vector>

#include "core/page_warmer.h"

namespace kdmesh {
namespace {

using Ranges = std::vector<PageWarmer::Range>;

/// Fresh anonymous memory of `bytes`, unmapped on destruction.
struct Mapping {
  explicit Mapping(std::size_t bytes) : size(bytes) {
    void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    base = p == MAP_FAILED ? nullptr : static_cast<unsigned char*>(p);
  }
  ~Mapping() {
    if (base) munmap(base, size);
  }
  std::size_t resident_pages() const {
    const std::size_t page = std::size_t(sysconf(_SC_PAGESIZE));
    std::vector<unsigned char> in((size + page - 1) / page);
    if (mincore(base, size, in.data()) != 0) return 0;
    std::size_t count = 0;
    for (unsigned char c : in) count += c & 1;
    return count;
  }
  unsigned char* base;
  std::size_t size;
};

/// Waits up to 20 s for the warmer to report `bytes`.
bool wait_for(const PageWarmer& w, std::size_t bytes) {
  for (int i = 0; i < 2000 && w.bytes() < bytes; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  return w.bytes() >= bytes;
}

TEST(PageWarmer, MakesFreshPagesResident) {
  const std::size_t bytes = std::size_t(64) << 20;
  Mapping m(bytes);
  ASSERT_NE(m.base, nullptr);
  ASSERT_EQ(m.resident_pages(), 0u);
  PageWarmer w(Ranges{{m.base, m.base + bytes}});
  if (!wait_for(w, bytes) && w.bytes() == 0) GTEST_SKIP() << "this system cannot populate pages";
  w.stop();
  EXPECT_EQ(w.bytes(), bytes);
  EXPECT_EQ(m.resident_pages(), bytes / std::size_t(sysconf(_SC_PAGESIZE)));
}

TEST(PageWarmer, OnlyWholePagesInsideTheRanges) {
  const std::size_t page = std::size_t(sysconf(_SC_PAGESIZE));
  Mapping m(16 * page);
  ASSERT_NE(m.base, nullptr);
  // [page + 1, 5 pages - 1) holds two whole pages, [2 pages, 4 pages); an empty and a
  // reversed range hold none.
  PageWarmer w(Ranges{{m.base + page + 1, m.base + 5 * page - 1},
                      {m.base + 8 * page, m.base + 8 * page},
                      {m.base + 12 * page, m.base + 10 * page}});
  wait_for(w, 2 * page);
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // time to overshoot, if it would
  w.stop();
  if (w.bytes() == 0) GTEST_SKIP() << "this system cannot populate pages";
  EXPECT_EQ(w.bytes(), 2 * page);
  EXPECT_EQ(m.resident_pages(), 2u);
  std::vector<unsigned char> in(16);
  ASSERT_EQ(mincore(m.base, 16 * page, in.data()), 0);
  EXPECT_TRUE((in[2] & 1) && (in[3] & 1));
}

TEST(PageWarmer, ContentsStayWhileAnotherThreadWrites) {
  // The warmer runs over memory being written: every value written is still there, and the
  // values written before it started too.
  const std::size_t n = std::size_t(16) << 20;  // 64 MB of words
  std::vector<std::uint32_t> v;
  v.reserve(n);
  v.resize(n / 2);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = std::uint32_t(i * 2654435761u);
  PageWarmer w(Ranges{{v.data(), v.data() + n}});
  for (std::size_t i = n / 2; i < n; ++i) v.push_back(std::uint32_t(i * 2654435761u));
  w.stop();
  ASSERT_EQ(v.size(), n);
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < n; ++i) wrong += v[i] != std::uint32_t(i * 2654435761u);
  EXPECT_EQ(wrong, 0u);
}

TEST(PageWarmer, StopReturnsBeforeTheRangeIsDone) {
  const std::size_t bytes = std::size_t(1) << 30;
  Mapping m(bytes);
  ASSERT_NE(m.base, nullptr);
  PageWarmer w(Ranges{{m.base, m.base + bytes}});
  w.stop();
  EXPECT_LT(w.bytes(), bytes / 2);
  EXPECT_EQ(m.resident_pages() * std::size_t(sysconf(_SC_PAGESIZE)), w.bytes());
}

}  // namespace
}  // namespace kdmesh
