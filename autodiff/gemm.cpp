// The GEMM backend's per-thread setup (gemm.h).

#include "autodiff/gemm.h"

#include <mutex>

#include "autodiff/check.h"
#include "autodiff/flop_count.h"

namespace hnn::ad::detail {

// Note [One BLAS thread per engine thread]: the engine splits batches over its own threads, so
// each GEMM must run on the thread that calls it. The pthreads build of OpenBLAS that this
// links keeps one global thread count, but the OpenMP build (which LD_LIBRARY_PATH can swap in
// under the same soname, as bench/compare's tuned environment does) reads it from the calling
// thread's OpenMP settings: a worker that never set it inherits OMP_NUM_THREADS and starts a
// team of its own for every product. That made the 2-thread LNN step four times slower than
// the 1-thread one (docs/threads.md). So every thread sets it, once, before its first GEMM.
void init_gemm() {
#ifdef HNN_HAVE_OPENBLAS
  if (t_gemm_ready) return;
  t_gemm_ready = true;
  static std::mutex setting;  // OpenBLAS's setter resizes shared buffers: one thread at a time
  std::lock_guard lock(setting);
  openblas_set_num_threads(1);
#endif
}

std::atomic<bool> g_counting_flops{false};

namespace {
std::atomic<std::uint64_t> g_flops{0};
}

void count_flops(std::uint64_t flops) { g_flops.fetch_add(flops, std::memory_order_relaxed); }

}  // namespace hnn::ad::detail

namespace hnn::ad {

GemmFlopCounter::GemmFlopCounter() {
  HNN_AD_CHECK(!detail::g_counting_flops.exchange(true), "GemmFlopCounter: one at a time");
  detail::g_flops.store(0);
}
GemmFlopCounter::~GemmFlopCounter() { detail::g_counting_flops.store(false); }
std::uint64_t GemmFlopCounter::flops() const { return detail::g_flops.load(); }

}  // namespace hnn::ad
