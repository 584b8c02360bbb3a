#include "autodiff/parallel.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "autodiff/check.h"

namespace hnn::ad {

namespace {

thread_local bool g_inside_part = false;

// Workers 1..n-1 wait for the job generation to change, run their part (if the job has one
// for them), and count down `pending_`: every worker answers every job, so none can miss one
// or see one twice. One job at a time: a caller that finds the pool busy runs its parts itself, in
// the same blocks, so results never depend on who got the pool.
class Pool {
 public:
  explicit Pool(int threads) : errors_(std::size_t(threads)) {
    for (int i = 1; i < threads; ++i) workers_.emplace_back([this, i] { work(i); });
  }
  ~Pool() {
    stop_.store(true);
    generation_.fetch_add(1);
    generation_.notify_all();
    for (std::thread& t : workers_) t.join();
  }
  int threads() const { return int(workers_.size()) + 1; }

  void run(int parts, PartFn part) {
    std::unique_lock lock(busy_, std::try_to_lock);
    if (!lock.owns_lock() || parts > threads()) return serial(parts, part);
    job_ = &part;
    parts_ = parts;
    std::fill(errors_.begin(), errors_.end(), nullptr);
    pending_.store(threads() - 1);
    generation_.fetch_add(1);
    generation_.notify_all();
    run_part(0);
    for (int left = pending_.load(); left != 0; left = pending_.load()) pending_.wait(left);
    for (const std::exception_ptr& e : errors_) {
      if (e) std::rethrow_exception(e);
    }
  }

 private:
  static void serial(int parts, PartFn part) {
    for (int i = 0; i < parts; ++i) part(i);
  }

  void run_part(int i) {
    g_inside_part = true;
    try {
      (*job_)(i);
    } catch (...) {
      errors_[std::size_t(i)] = std::current_exception();
    }
    g_inside_part = false;
  }

  void work(int i) {
    std::uint64_t seen = 0;
    while (true) {
      generation_.wait(seen);
      seen = generation_.load();
      if (stop_.load()) return;
      if (i < parts_) run_part(i);
      if (pending_.fetch_sub(1) == 1) pending_.notify_one();
    }
  }

  std::vector<std::thread> workers_;
  std::vector<std::exception_ptr> errors_;
  std::mutex busy_;
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<int> pending_{0};
  std::atomic<bool> stop_{false};
  const PartFn* job_ = nullptr;
  int parts_ = 0;
};

int default_threads() {
  return int(std::clamp<unsigned>(std::thread::hardware_concurrency(), 1, 8));
}

std::mutex g_pool_mutex;
int g_threads = default_threads();
std::shared_ptr<Pool> g_pool;

std::shared_ptr<Pool> pool() {
  std::lock_guard lock(g_pool_mutex);
  if (!g_pool || g_pool->threads() != g_threads) g_pool = std::make_shared<Pool>(g_threads);
  return g_pool;
}

}  // namespace

void set_num_threads(int n) {
  HNN_AD_CHECK(n >= 1, "set_num_threads: need at least 1 thread, got {}", n);
  std::lock_guard lock(g_pool_mutex);
  g_threads = n;
}

int num_threads() {
  std::lock_guard lock(g_pool_mutex);
  return g_threads;
}

void parallel_for(int parts, PartFn part) {
  HNN_AD_CHECK(parts >= 1, "parallel_for: need at least 1 part, got {}", parts);
  if (parts == 1 || g_inside_part) {
    for (int i = 0; i < parts; ++i) part(i);
    return;
  }
  pool()->run(parts, part);
}

RowBlock row_block(Eigen::Index rows, int parts, int i) {
  return {rows * i / parts, rows * (i + 1) / parts};
}

int parts_for(Eigen::Index rows, Eigen::Index min_rows) {
  const Eigen::Index by_size =
      std::max<Eigen::Index>(1, rows / std::max<Eigen::Index>(min_rows, 1));
  return int(std::min<Eigen::Index>(num_threads(), by_size));
}

}  // namespace hnn::ad
