#pragma once
// Result files are written atomically: a temporary file in the same folder, flushed and
// fsync'ed, then renamed over the target. A kill at any moment leaves the old file or the new
// one, never a torn one.

#include <filesystem>
#include <string_view>

namespace hnn::tasks {

void write_file_atomic(const std::filesystem::path& path, std::string_view content);

}  // namespace hnn::tasks
