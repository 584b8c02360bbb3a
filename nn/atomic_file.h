#pragma once
// The one atomic file writer of the project: parameter files (nn/parameter_file.h), training
// checkpoints, run folders and every result file go through it. It lives in nn, the lowest
// module that writes files, so that tasks/ and apps/ use the same one.

#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>

namespace hnn::nn {

/// A file that could not be written. what() is "cannot write '<path>' (<step>): <system
/// message>", e.g. "cannot write 'out/x.csv' (its folder 'out' does not exist): No such file or
/// directory".
class FileWriteError : public std::system_error {
 public:
  FileWriteError(std::error_code code, const std::filesystem::path& path, std::string step);
  const std::filesystem::path& path() const { return path_; }
  /// What failed: "its folder 'D' does not exist", "'F' is a file, not a folder", "creating a
  /// temporary file in its folder", "writing", "flushing to disk", "closing" or "renaming into
  /// place".
  const std::string& step() const { return step_; }

 private:
  std::filesystem::path path_;
  std::string step_;
};

/// Writes `content` to `path` so that a kill at any moment leaves the old file or the new one,
/// never a torn one: a temporary file in the same folder ("<name>.tmp.<pid>-<n>", created with
/// mode 0644 less the umask), written, fsync'ed and closed, then renamed over `path`, and the
/// folder fsync'ed so that the rename itself is durable (best effort: some file systems refuse).
/// Throws FileWriteError on failure and then leaves no temporary file behind.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

/// A std::filesystem error as one line naming the path and why, e.g. "'afile/sub': 'afile' is a
/// file, not a folder (cannot create directories)", for the programs' error line.
std::string filesystem_error_line(const std::filesystem::filesystem_error& e);

}  // namespace hnn::nn
