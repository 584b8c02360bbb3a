#include "tasks/report/run_folder.h"

#include <fmt/format.h>

#include "nn/atomic_file.h"
#include "tasks/error.h"
#include "tasks/report/json_values.h"

namespace hnn::tasks {

namespace fs = std::filesystem;

void RunFolder::create() const {
  HNN_TASKS_CHECK(!fs::exists(dir_) || fs::is_directory(dir_), "'{}' is a file, not a folder",
                  dir_.string());
  fs::create_directories(dir_);
}

void RunFolder::write_text(std::string_view name, std::string_view content) const {
  nn::write_file_atomic(file(name), content);
}

void RunFolder::write_metrics(const nlohmann::json& metrics) const {
  write_text("metrics.json", metrics.dump(2) + "\n");
}

void RunFolder::write_loss_curve(const std::vector<CurvePoint>& curve,
                                 std::string_view units) const {
  std::string csv = fmt::format("step,train_loss{},test_loss{}\n", units, units);
  for (const CurvePoint& p : curve)
    csv += fmt::format("{},{:.9g},{:.9g}\n", p.step, p.train_loss, p.test_loss);
  write_text("loss_curve.csv", csv);
}

nlohmann::json RunFolder::read_metrics() const {
  const fs::path metrics = file("metrics.json");
  HNN_TASKS_CHECK(fs::exists(metrics), "cannot read '{}': is '{}' a run folder of `hnn train`?",
                  metrics.string(), dir_.string());
  return read_json_file(metrics);
}

}  // namespace hnn::tasks
