// The engine's worker pool (autodiff/parallel.h): every part of every job runs exactly once,
// whoever claims it (Note [Claimed parts]), also with jobs from several threads at once and with
// nested calls; the lowest failing part's exception reaches the caller; the pool survives a
// change of thread count; every part runs in its caller's floating-point mode.

#include "autodiff/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <bit>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "autodiff/check.h"
#include "autodiff/float_mode.h"

namespace ad = hnn::ad;

namespace {

// A few microseconds of work, so that workers wake in time to claim parts too.
void Busy() {
  volatile int sink = 0;
  for (int i = 0; i < 2000; ++i) sink = sink + i;
}

// Runs `jobs` jobs of 1..threads parts, counting each part's runs; returns the counts that are
// not exactly one.
int WrongCounts(int jobs, int threads) {
  int wrong = 0;
  std::vector<std::atomic<int>> runs(static_cast<std::size_t>(threads));
  for (int job = 0; job < jobs; ++job) {
    const int parts = 1 + job % threads;
    for (int i = 0; i < parts; ++i) runs[std::size_t(i)].store(0);
    ad::parallel_for(parts, [&](int i) {
      Busy();
      runs[std::size_t(i)].fetch_add(1);
    });
    for (int i = 0; i < parts; ++i) wrong += runs[std::size_t(i)].load() != 1;
  }
  return wrong;
}

TEST(ParallelFor, RunsEveryPartOfEveryJobExactlyOnce) {
  for (int threads : {1, 2, 4}) {
    ad::set_num_threads(threads);
    EXPECT_EQ(WrongCounts(20000, threads), 0) << threads << " threads";
  }
  ad::set_num_threads(2);
}

TEST(ParallelFor, JobsFromSeveralThreadsAndNestedCallsRunEveryPartOnce) {
  ad::set_num_threads(2);
  std::atomic<int> wrong{0};
  std::vector<std::thread> callers;
  for (int t = 0; t < 3; ++t) {
    callers.emplace_back([&] {
      for (int job = 0; job < 3000; ++job) {
        std::atomic<int> inner{0};
        std::atomic<int> outer{0};
        ad::parallel_for(2, [&](int) {
          Busy();
          outer.fetch_add(1);
          ad::parallel_for(2, [&](int) { inner.fetch_add(1); });  // nested: serial
        });
        wrong += outer.load() != 2 || inner.load() != 4;
      }
    });
  }
  for (std::thread& c : callers) c.join();
  EXPECT_EQ(wrong.load(), 0);
}

TEST(ParallelFor, RethrowsTheLowestFailingPartsException) {
  ad::set_num_threads(2);
  for (int job = 0; job < 200; ++job) {
    try {
      ad::parallel_for(2, [](int i) { throw std::runtime_error("part " + std::to_string(i)); });
      FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "part 0");
    }
  }
  EXPECT_EQ(WrongCounts(100, 2), 0) << "the pool works after failed jobs";
}

// Pinned jobs (Note [Pinned parts]): part 0 on the caller, part i on thread i unless the caller
// found it not started and ran it itself (never on another worker), each part once, mixed with
// claimed jobs; nested calls run serially; too many parts refused.
TEST(ParallelForEachThread, RunsPartIOnThreadIOrOnTheCaller) {
  for (int threads : {2, 4}) {
    ad::set_num_threads(threads);
    const std::thread::id caller = std::this_thread::get_id();
    std::vector<std::thread::id> worker(static_cast<std::size_t>(threads));
    std::vector<std::atomic<int>> runs(static_cast<std::size_t>(threads));
    int wrong = 0;
    for (int job = 0; job < 3000; ++job) {
      const int parts = job % 3 == 0 ? threads : 1 + job % threads;
      for (int i = 0; i < parts; ++i) runs[std::size_t(i)].store(0);
      std::vector<std::thread::id> seen(static_cast<std::size_t>(parts));
      ad::parallel_for_each_thread(parts, [&](int i) {
        Busy();
        seen[std::size_t(i)] = std::this_thread::get_id();
        runs[std::size_t(i)].fetch_add(1);
      });
      wrong += seen[0] != caller;
      for (int i = 0; i < parts; ++i) {
        wrong += runs[std::size_t(i)].load() != 1;
        const std::thread::id id = seen[std::size_t(i)];
        if (i == 0 || id == caller) continue;
        if (worker[std::size_t(i)] == std::thread::id()) worker[std::size_t(i)] = id;
        wrong += id != worker[std::size_t(i)];
      }
      if (job % 7 == 0) wrong += WrongCounts(3, threads);  // claimed jobs in between
    }
    for (int i = 1; i < threads; ++i) {
      for (int j = i + 1; j < threads; ++j) {
        const bool both = worker[std::size_t(i)] != std::thread::id();
        wrong += both && worker[std::size_t(i)] == worker[std::size_t(j)];
      }
    }
    EXPECT_EQ(wrong, 0) << threads << " threads";
    EXPECT_THROW(ad::parallel_for_each_thread(threads + 1, [](int) {}), ad::Error);
  }
  ad::set_num_threads(2);
  std::atomic<int> inner{0};
  ad::parallel_for_each_thread(2, [&](int) {
    EXPECT_EQ(ad::available_threads(), 1);
    ad::parallel_for_each_thread(2, [&](int) { inner.fetch_add(1); });  // nested: serial
  });
  EXPECT_EQ(inner.load(), 4);
  EXPECT_EQ(ad::available_threads(), 2);
}

// A product below float's normal range: 1e-40 as it is, 0 with denormals flushed. Its factors
// are volatile, so that the compiler cannot fold it.
float DenormalProduct() {
  volatile float tiny = 1e-30f, small = 1e-10f;
  return tiny * small;
}

// Each part's product, and how many of a run of two-part jobs had part 1 on a worker.
struct PartProducts {
  int zero = 0, nonzero = 0, on_a_worker = 0;
};
PartProducts ProductsInParts(int jobs) {
  PartProducts out;
  const std::thread::id caller = std::this_thread::get_id();
  for (int job = 0; job < jobs; ++job) {
    float product[2];
    std::thread::id ran[2];
    ad::parallel_for_each_thread(2, [&](int i) {
      for (int k = 0; k < 10; ++k) Busy();  // long enough for the worker to start its part
      product[i] = DenormalProduct();
      ran[i] = std::this_thread::get_id();
    });
    // By its bits: with denormals-are-zero on this thread, a comparison would read 1e-40 as 0.
    for (float p : product) (std::bit_cast<std::uint32_t>(p) == 0 ? out.zero : out.nonzero) += 1;
    out.on_a_worker += ran[1] != caller;
  }
  return out;
}

TEST(FlushDenormals, FlushesOnTheCallersThreadAndInItsPartsAndRestoresTheModeAfter) {
#if !defined(__SSE3__)
  GTEST_SKIP() << "this build leaves the floating-point mode alone";
#endif
  ad::set_num_threads(2);
  const ad::FloatMode before = ad::float_mode();
  ASSERT_NE(std::bit_cast<std::uint32_t>(DenormalProduct()), 0u) << "denormals flushed already";
  EXPECT_EQ(ProductsInParts(200).zero, 0);
  {
    const ad::FlushDenormals flush;
    EXPECT_EQ(std::bit_cast<std::uint32_t>(DenormalProduct()), 0u);
    const PartProducts inside = ProductsInParts(200);
    EXPECT_EQ(inside.nonzero, 0);
    EXPECT_GT(inside.on_a_worker, 0) << "no part ran on a worker: the test says nothing";
  }
  EXPECT_EQ(ad::float_mode(), before);
  EXPECT_NE(std::bit_cast<std::uint32_t>(DenormalProduct()), 0u);
  // The workers that flushed for the last job follow the caller back.
  const PartProducts after = ProductsInParts(200);
  EXPECT_EQ(after.zero, 0);
  EXPECT_GT(after.on_a_worker, 0);
}

// Element blocks tile [0, n) in order and start at whole 16-element packets.
TEST(ElementBlocks, TileTheArrayAtPacketBoundaries) {
  for (Eigen::Index n : {0, 5, 16, 40000, 40001}) {
    for (int parts : {1, 2, 3, 7}) {
      Eigen::Index next = 0;
      for (int i = 0; i < parts; ++i) {
        const ad::RowBlock b = ad::element_block(n, parts, i);
        EXPECT_EQ(b.begin, next) << n << " in " << parts;
        EXPECT_EQ(b.begin % 16 == 0 || b.begin == n, true) << n << " in " << parts;
        next = b.end;
      }
      EXPECT_EQ(next, n) << n << " in " << parts;
    }
  }
}

}  // namespace
