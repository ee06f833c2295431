// sdk/parallel.hpp: loops shared out only where a second thread can take a
// share, each iteration run once either way; sdk/memory.hpp: large_vector.
#include <gtest/gtest.h>

#include <omp.h>

#include <cstdint>
#include <vector>

#include <thermostamp/sdk/memory.hpp>
#include <thermostamp/sdk/parallel.hpp>

#include "solve/subnormals.hpp"

namespace ts::test {
namespace {

struct Record {
  std::vector<int> count, thread;
  explicit Record(int n) : count(n, 0), thread(n, -1) {}
  void run(int n, bool worthwhile, int chunk) {
    sdk::for_each_index(n, worthwhile, chunk, [this](int i) {
      ++count[i];
      thread[i] = omp_get_thread_num();
    });
  }
};

class SdkParallel : public ::testing::Test {
 protected:
  void SetUp() override {
    threads_ = omp_get_max_threads();
    levels_ = omp_get_max_active_levels();
    omp_set_num_threads(2);
    omp_set_max_active_levels(1);
  }
  void TearDown() override {
    omp_set_num_threads(threads_);
    omp_set_max_active_levels(levels_);
  }
  int threads_ = 1, levels_ = 1;
};

TEST_F(SdkParallel, SharesOutOnlyWhereASecondThreadCanTakeAShare) {
  const int n = 1000;
  // Two threads and the loop worth it: chunks of 128 dealt round robin.
  Record shared(n);
  shared.run(n, true, 128);
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(shared.count[i], 1) << i;
    EXPECT_EQ(shared.thread[i], (i / 128) % 2) << i;
  }
  // Contiguous ranges without a chunk.
  Record ranges(n);
  ranges.run(n, true, 0);
  for (int i = 0; i < n; ++i) EXPECT_EQ(ranges.thread[i], i < n / 2 ? 0 : 1) << i;
  // Not worth it, or one thread in all: in order on the calling thread.
  Record small(n);
  small.run(n, false, 128);
  omp_set_num_threads(1);
  EXPECT_FALSE(sdk::team_available(true));
  Record alone(n);
  alone.run(n, true, 128);
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(small.count[i], 1);
    ASSERT_EQ(alone.count[i], 1);
    EXPECT_EQ(small.thread[i], 0);
    EXPECT_EQ(alone.thread[i], 0);
  }
  omp_set_num_threads(2);
  EXPECT_TRUE(sdk::team_available(true));
}

TEST_F(SdkParallel, RunsOnTheCallingThreadInsideAnActiveRegion) {
  // As in the kernel's contact task beside the element blocks: a nested
  // region would get one thread, so the loop runs without one.
  const int n = 600;
  std::vector<Record> rec(2, Record(n));
  std::vector<int> available(2, -1);
#pragma omp parallel num_threads(2)
  {
    const int me = omp_get_thread_num();
    available[me] = sdk::team_available(true);
    rec[me].run(n, true, 128);
  }
  for (int t = 0; t < 2; ++t) {
    EXPECT_EQ(available[t], 0) << t;
    for (int i = 0; i < n; ++i) {
      ASSERT_EQ(rec[t].count[i], 1);
      EXPECT_EQ(rec[t].thread[i], t);
    }
  }
}

// large_vector: arrays from 1 MiB up start on a 2 MiB boundary (where a
// huge page can back them), smaller ones as std::allocator gives them; both
// keep their contents as a std::vector does (growth, copy).
TEST(SdkMemory, LargeVectorsAlignToHugePagesAndKeepTheirContents) {
  sdk::large_vector<double> big(sdk::kLargeArrayBytes / sizeof(double) + 1, 0.0);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(big.data()) % sdk::kHugePageBytes, 0u);
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<double>(i);
  big.resize(3 * big.size(), -1.0);  // reallocates: the first entries move along
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(big.data()) % sdk::kHugePageBytes, 0u);
  for (std::size_t i = 0; i < big.size() / 3; i += 4099) EXPECT_EQ(big[i], static_cast<double>(i));
  EXPECT_EQ(big.back(), -1.0);
  sdk::large_vector<int> small(100, 7);
  const sdk::large_vector<int> copy = small;
  EXPECT_EQ(copy, small);
  small.clear();
  small.shrink_to_fit();
  EXPECT_TRUE(small.empty());
}

// What one thread computes with subnormal numbers: a product whose exact
// value is subnormal (flushed: 0) and the smallest subnormal as an operand
// (read as zero: its double is 0).
struct SubnormalProbe {
  bool flushed = false;
  double product = -1, doubled = -1;
};
SubnormalProbe probe_subnormals() {
  volatile double a = 1e-300, b = 1e-10, tiny = 4.9406564584124654e-324;
  SubnormalProbe p;
  p.flushed = subnormals_flushed_here();
  p.product = a * b;
  p.doubled = tiny * 2.0;
  return p;
}

// Simulation::run flushes subnormals to zero on every thread of the run
// (solve/subnormals.hpp) and leaves the threads as it found them: checked
// with the guard it uses, on a team of two threads, and with a guard asked
// not to flush.
TEST_F(SdkParallel, SubnormalsFlushedOnEveryThreadAndRestoredAfter) {
  const SubnormalProbe before = probe_subnormals();
  ASSERT_FALSE(before.flushed) << "the test process starts with IEEE subnormals";
  EXPECT_GT(before.product, 0.0);
  EXPECT_EQ(before.doubled, 2 * 4.9406564584124654e-324);
  std::vector<SubnormalProbe> seen(2);
  {
    const SubnormalsFlushed guard(true);
#if defined(__x86_64__) || defined(__aarch64__)
    EXPECT_TRUE(guard.active());
#endif
    if (guard.active()) {
#pragma omp parallel num_threads(2)
      seen[omp_get_thread_num()] = probe_subnormals();
      for (int t = 0; t < 2; ++t) {
        EXPECT_TRUE(seen[t].flushed) << t;
        EXPECT_EQ(seen[t].product, 0.0) << t;
        EXPECT_EQ(seen[t].doubled, 0.0) << t;
      }
    }
  }
#pragma omp parallel num_threads(2)
  seen[omp_get_thread_num()] = probe_subnormals();
  for (int t = 0; t < 2; ++t) {
    EXPECT_FALSE(seen[t].flushed) << t;
    EXPECT_EQ(seen[t].product, before.product) << t;
  }
  {
    const SubnormalsFlushed kept(false);
    EXPECT_FALSE(kept.active());
    EXPECT_FALSE(probe_subnormals().flushed);
  }
}

}  // namespace
}  // namespace ts::test
