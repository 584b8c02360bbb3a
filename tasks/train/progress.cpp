#include "tasks/train/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>

namespace hnn::tasks {

Progress::Progress(std::string label, long total, bool quiet)
    : label_(std::move(label)),
      total_(total > 0 ? total : 1),
      quiet_(quiet),
      terminal_(isatty(fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()),
      last_print_(start_) {}

void Progress::update(long done, double loss) {
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  if (terminal_) {
    // Redraw at most 10 times a second.
    if (now - last_print_ < std::chrono::milliseconds(100)) return;
    last_print_ = now;
    print(done, loss, false);
    return;
  }
  const long decile = done * 10 / total_;  // plain output: one line per 10%
  if (decile == last_logged_decile_) return;
  last_logged_decile_ = decile;
  print(done, loss, false);
}

void Progress::finish(double loss) {
  if (!quiet_) print(total_, loss, true);
}

void Progress::stop(long done, double loss) {
  if (!quiet_) print(done, loss, true);
}

void Progress::print(long done, double loss, bool final) {
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = seconds > 0 ? double(done) / seconds : 0.0;
  const double left = rate > 0 ? double(total_ - done) / rate : 0.0;
  const std::string stats =
      fmt::format("{}/{} steps  loss {:.4e}  {:.0f} steps/s  {}", done, total_, loss, rate,
                  final ? fmt::format("{:.1f} s", seconds) : fmt::format("{:.0f} s left", left));
  if (terminal_) {
    constexpr int kWidth = 24;
    const int filled = int(kWidth * done / total_);
    fmt::print(stderr, "\r{} [{}{}] {}\033[K{}", label_, std::string(filled, '#'),
               std::string(kWidth - filled, '.'), stats, final ? "\n" : "");
  } else {
    fmt::print(stderr, "{}: {}\n", label_, stats);
  }
  std::fflush(stderr);
}

}  // namespace hnn::tasks
