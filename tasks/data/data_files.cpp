#include "tasks/data/data_files.h"

#include <cstdlib>
#include <filesystem>

namespace hnn::tasks {

std::string default_data_path(const std::string& relative) {
  namespace fs = std::filesystem;
  if (const char* dir = std::getenv("HNN_DATA_DIR")) return (fs::path(dir) / relative).string();
  const fs::path source = fs::path(HNN_SOURCE_DATA_DIR) / relative;
  if (fs::exists(source)) return source.string();
  return (fs::path(HNN_INSTALL_DATA_DIR) / relative).string();
}

}  // namespace hnn::tasks
