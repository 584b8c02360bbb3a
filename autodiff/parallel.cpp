#include "autodiff/parallel.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "autodiff/check.h"
#include "autodiff/float_mode.h"

namespace hnn::ad {

namespace {

thread_local bool g_inside_part = false;
std::atomic<long> g_stolen{0};  // pinned parts the caller ran for a worker (Note [Pinned parts])

// Note [Claimed parts]: a job's parts are claimed one at a time from one atomic word, by the
// caller and by every worker that wakes while parts are left; the caller, once nothing is left
// to claim, waits only for the parts that workers claimed and are running. A worker that the
// scheduler has not woken yet (a shared, loaded machine) therefore costs nothing: waiting for
// every worker to answer every job stalled each op for a time slice there, making two threads
// several times slower than one. Part i computes block i whoever runs it, so results never
// depend on who claimed what. A job may have more parts than the pool has threads (an
// evaluation's rollouts, one part each): whoever finishes a part claims the next. One job at a
// time: a caller that finds the pool busy runs its parts itself.
// Note [Pinned parts]: a job of parallel_for_each_thread runs part i on thread i. Claimed parts
// go to whoever gets there first, so from one call to the next a thread may run another part;
// where parts keep buffers per thread (a step split by rows: each thread's tape) and the parts'
// sizes differ by a row, every swap resized those buffers, allocating in steady state. A pinned
// job is published with all its parts claimed; each worker whose index is below the parts starts
// its own, and the caller runs part 0. A part is started once, by whoever marks it first: the
// caller, done with part 0, starts any part whose worker has not (a worker the host has not
// scheduled would otherwise hold the whole job up, and the split would lose to one thread).
// Parts taken so are counted (stolen_parts()); they resize buffers as claimed parts did.
class Pool {
 public:
  explicit Pool(int threads)  // sized once: a step's jobs allocate nothing
      : errors_(std::size_t(threads)), started_(std::make_unique<std::atomic<bool>[]>(threads)) {
    for (int i = 1; i < threads; ++i) workers_.emplace_back([this, i] { work(i); });
  }
  ~Pool() {
    stop_.store(true);
    claim_.fetch_add(kGeneration);  // a change every waiting worker sees
    claim_.notify_all();
    for (std::thread& t : workers_) t.join();
  }
  int threads() const { return int(workers_.size()) + 1; }

  // pinned: part i runs on thread i (the caller is 0), none is claimed (Note [Pinned parts]).
  void run(int parts, PartFn part, bool pinned) {
    std::unique_lock lock(busy_, std::try_to_lock);
    if (!lock.owns_lock() || std::uint64_t(parts) > kField) return serial(parts, part);
    job_ = &part;
    mode_ = float_mode();
    if (errors_.size() < std::size_t(parts)) errors_.resize(std::size_t(parts));
    std::fill_n(errors_.begin(), parts, nullptr);
    done_.store(0, std::memory_order_relaxed);
    for (int i = 0; pinned && i < parts; ++i) started_[i].store(i == 0, std::memory_order_relaxed);
    generation_ += kGeneration;
    // Publishes the job (release: job_ and the reset counters are visible to whoever claims). A
    // pinned job is published with every part claimed.
    const std::uint64_t next = pinned ? std::uint64_t(parts) : 0;
    claim_.store(generation_ | (pinned ? kPinned : 0) | std::uint64_t(parts) << kPartsShift | next,
                 std::memory_order_release);
    claim_.notify_all();
    if (pinned) {
      run_part(0, parts);
      for (int i = 1; i < parts; ++i) {
        if (start(i)) {
          g_stolen.fetch_add(1, std::memory_order_relaxed);
          run_part(i, parts);
        }
      }
    } else {
      for (int i = claim().part; i >= 0; i = claim().part) run_part(i, parts);
    }
    for (int d = done_.load(std::memory_order_acquire); d != parts;
         d = done_.load(std::memory_order_acquire)) {
      done_.wait(d);
    }
    for (int i = 0; i < parts; ++i) {
      if (errors_[std::size_t(i)]) std::rethrow_exception(errors_[std::size_t(i)]);
    }
  }

 private:
  // The claim word: generation (bits 33..63, one step per job), whether the job is pinned (32),
  // the job's parts (16..31) and the next unclaimed part (0..15).
  static constexpr std::uint64_t kGeneration = std::uint64_t(1) << 33;
  static constexpr std::uint64_t kPinned = std::uint64_t(1) << 32;
  static constexpr int kPartsShift = 16;
  static constexpr std::uint64_t kField = 0xFFFF;
  static constexpr std::chrono::microseconds kSpin{500};  // Note [Brief spin]

  static void serial(int parts, PartFn part) {
    for (int i = 0; i < parts; ++i) part(i);
  }

  // Marks part i of a pinned job started; false when someone already had.
  bool start(int i) { return !started_[i].exchange(true, std::memory_order_acq_rel); }

  struct Claimed {
    int part = -1;           // -1: every part of the current job is claimed
    int parts = 0;           // of the job the part belongs to
    std::uint64_t word = 0;  // the claim word this saw last
  };

  // The next part of the current job.
  Claimed claim() {
    std::uint64_t word = claim_.load(std::memory_order_acquire);
    while ((word & kField) < ((word >> kPartsShift) & kField)) {
      if (claim_.compare_exchange_weak(word, word + 1, std::memory_order_acq_rel)) {
        return {int(word & kField), int((word >> kPartsShift) & kField), word};
      }
    }
    return {.word = word};
  }

  // In the caller's floating-point mode (Note [Denormals flushed] in float_mode.h).
  void run_part(int i, int parts) {
    set_float_mode(mode_);
    g_inside_part = true;
    try {
      (*job_)(i);
    } catch (...) {
      errors_[std::size_t(i)] = std::current_exception();
    }
    g_inside_part = false;
    if (done_.fetch_add(1, std::memory_order_acq_rel) + 1 == parts) done_.notify_one();
  }

  void work(int index) {
    std::uint64_t ran = 0;  // the generation of the last pinned job this worker ran its part of
    while (true) {
      // Claiming orders this after the job's publication, so job_ is the claimed part's job
      // (whose caller cannot publish another before this part is done).
      Claimed c = claim();
      for (; c.part >= 0; c = claim()) run_part(c.part, c.parts);
      if (stop_.load()) return;  // after the claim: a word seen after ~Pool's change means stop
      // A pinned job's part `index`, once: its caller waits for it, so job_ is still that job.
      const std::uint64_t generation = c.word & ~(kGeneration - 1);
      const int parts = int((c.word >> kPartsShift) & kField);
      if ((c.word & kPinned) && generation != ran && index < parts) {
        ran = generation;
        if (start(index)) run_part(index, parts);
        continue;  // the caller may have published the next job meanwhile
      }
      if (!spin_until_changed(c.word)) claim_.wait(c.word);  // until a new job or ~Pool
    }
  }

  // Note [Brief spin]: a training step hands the workers a job per op, often tens of
  // microseconds apart; a worker that goes to sleep in between is woken by a system call and
  // arrives late (tens of microseconds on a VM), by which time the caller has claimed its part.
  // So it watches the claim word for kSpin first (pausing, not yielding) and sleeps only after.
  // Bounded, so an idle pool burns no core. Waking a sleeping worker costs the caller about
  // 8-11 us on this project's 2-vCPU VMs, against 0.1-1 us for a watching one
  // (bench/parallel_bench: AfterGap); the serial stretches of the D-HNN, LNN and rollout steps
  // (Adam, small ops) outlast 50 us, and 500 us made those steps 4-13% faster (docs/threads.md).
  bool spin_until_changed(std::uint64_t word) const {
    const auto until = std::chrono::steady_clock::now() + kSpin;
    while (true) {
      for (int i = 0; i < 64; ++i) {
        if (claim_.load(std::memory_order_relaxed) != word) return true;
        pause();
      }
      if (std::chrono::steady_clock::now() > until) return false;
    }
  }

  static void pause() {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
  }

  std::vector<std::thread> workers_;
  std::vector<std::exception_ptr> errors_;  // per part
  std::mutex busy_;
  std::atomic<std::uint64_t> claim_{0};
  std::atomic<int> done_{0};
  std::atomic<bool> stop_{false};
  std::uint64_t generation_ = 0;  // the caller's copy (under busy_)
  const PartFn* job_ = nullptr;
  FloatMode mode_ = 0;                            // the caller's, published with job_
  std::unique_ptr<std::atomic<bool>[]> started_;  // per part of a pinned job
};

int default_threads() {
  return int(std::clamp<unsigned>(std::thread::hardware_concurrency(), 1, 8));
}

std::mutex g_pool_mutex;
// Atomic: every op reads it (parts_for), from every thread of an evaluation's rollouts, and a
// lock there was contended.
std::atomic<int> g_threads = default_threads();
std::shared_ptr<Pool> g_pool;

std::shared_ptr<Pool> pool() {
  std::lock_guard lock(g_pool_mutex);
  const int threads = g_threads.load(std::memory_order_relaxed);
  if (!g_pool || g_pool->threads() != threads) g_pool = std::make_shared<Pool>(threads);
  return g_pool;
}

}  // namespace

void set_num_threads(int n) {
  HNN_AD_CHECK(n >= 1, "set_num_threads: need at least 1 thread, got {}", n);
  std::lock_guard lock(g_pool_mutex);
  g_threads.store(n, std::memory_order_relaxed);
}

int num_threads() { return g_threads.load(std::memory_order_relaxed); }

long stolen_parts() { return g_stolen.load(std::memory_order_relaxed); }

int available_threads() { return g_inside_part ? 1 : num_threads(); }

namespace {

// A job on the pool; one part, or a call nested in a part, runs in turn on this thread.
void dispatch(int parts, PartFn part, bool pinned) {
  if (parts == 1 || g_inside_part) {
    for (int i = 0; i < parts; ++i) part(i);
    return;
  }
  pool()->run(parts, part, pinned);
}

}  // namespace

void parallel_for(int parts, PartFn part) {
  HNN_AD_CHECK(parts >= 1, "parallel_for: need at least 1 part, got {}", parts);
  dispatch(parts, part, /*pinned=*/false);
}

void parallel_for_each_thread(int parts, PartFn part) {
  HNN_AD_CHECK(parts >= 1 && parts <= num_threads(),
               "parallel_for_each_thread: need 1 to {} parts (the threads), got {}", num_threads(),
               parts);
  dispatch(parts, part, /*pinned=*/true);
}

RowBlock row_block(Eigen::Index rows, int parts, int i) {
  return {rows * i / parts, rows * (i + 1) / parts};
}

RowBlock element_block(Eigen::Index n, int parts, int i) {
  constexpr Eigen::Index kLanes = 16;  // an AVX-512 packet of floats; whole packets of any ISA
  const RowBlock lanes = row_block((n + kLanes - 1) / kLanes, parts, i);
  return {std::min(n, lanes.begin * kLanes), std::min(n, lanes.end * kLanes)};
}

int parts_for(Eigen::Index rows, Eigen::Index min_rows) {
  const Eigen::Index by_size =
      std::max<Eigen::Index>(1, rows / std::max<Eigen::Index>(min_rows, 1));
  return int(std::min<Eigen::Index>(available_threads(), by_size));
}

}  // namespace hnn::ad
