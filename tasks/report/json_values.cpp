#include "tasks/report/json_values.h"

#include <fstream>

namespace hnn::tasks {

nlohmann::json read_json_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  HNN_TASKS_CHECK(in.good(), "cannot read '{}'", path.string());
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw Error(fmt::format("'{}' is not valid JSON: {}", path.string(), e.what()));
  }
}

}  // namespace hnn::tasks
