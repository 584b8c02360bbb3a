#pragma once
// Progress of long work: a live bar on a terminal, plain log lines otherwise (CI logs, files).

#include <chrono>
#include <string>

namespace hnn::tasks {

class Progress {
 public:
  /// `total` units of work; `quiet` prints nothing at all.
  Progress(std::string label, long total, bool quiet = false);
  /// Reports `done` units, with the current loss.
  void update(long done, double loss);
  /// Ends the bar (a final line).
  void finish(double loss);
  /// Ends the bar early, at `done` units (work stopped on request).
  void stop(long done, double loss);

 private:
  void print(long done, double loss, bool final);

  std::string label_;
  long total_;
  bool quiet_, terminal_;
  std::chrono::steady_clock::time_point start_, last_print_;
  long last_logged_decile_ = -1;
};

}  // namespace hnn::tasks
