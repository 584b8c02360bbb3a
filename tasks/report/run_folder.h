#pragma once
// A run folder (RUN/): every file a run writes goes through here, each atomically. Every task
// writes metrics.json, loss_curve.csv and params.bin, and training checkpoints into
// RUN/checkpoint; a task adds its own files (rollout.csv, figures) by name.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace hnn::tasks {

/// One point of a loss curve: the losses on both splits after `step` training steps.
struct CurvePoint {
  long step;
  double train_loss, test_loss;
};

class RunFolder {
 public:
  explicit RunFolder(std::filesystem::path dir) : dir_(std::move(dir)) {}

  const std::filesystem::path& path() const { return dir_; }
  std::filesystem::path file(std::string_view name) const { return dir_ / name; }
  std::filesystem::path params_file() const { return file("params.bin"); }
  std::filesystem::path checkpoint_dir() const { return file("checkpoint"); }

  /// Creates the folder; throws Error when the path is a file.
  void create() const;
  /// Writes RUN/name atomically.
  void write_text(std::string_view name, std::string_view content) const;
  void write_metrics(const nlohmann::json& metrics) const;
  /// loss_curve.csv: step,train_loss<units>,test_loss<units>; `units` names losses in other
  /// units than the file's ("_standardised": a data run's, as metrics.json's keys say).
  void write_loss_curve(const std::vector<CurvePoint>& curve, std::string_view units = {}) const;
  /// metrics.json; throws Error saying the folder is not a finished run when it is missing.
  nlohmann::json read_metrics() const;

 private:
  std::filesystem::path dir_;
};

}  // namespace hnn::tasks
