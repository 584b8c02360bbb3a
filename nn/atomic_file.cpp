#include "nn/atomic_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>

namespace hnn::nn {

namespace fs = std::filesystem;

FileWriteError::FileWriteError(std::error_code code, const fs::path& path, std::string step)
    : std::system_error(code, fmt::format("cannot write '{}' ({})", path.string(), step)),
      path_(path),
      step_(std::move(step)) {}

namespace {

std::error_code last_error() { return {errno, std::generic_category()}; }

// Creates a temporary file next to `path` that no other writer uses: the process id tells
// processes apart and the counter threads and calls; O_EXCL skips a leftover of an earlier
// process that had the same id. Returns the descriptor, or -1 with errno set.
int create_temporary(const fs::path& path, fs::path& temp) {
  static std::atomic<unsigned long> counter{0};
  while (true) {
    temp = path;
    temp += fmt::format(".tmp.{}-{}", ::getpid(), counter++);
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0 || errno != EEXIST) return fd;
  }
}

// The first of `p` and its ancestors that is a regular file (where a folder should be), or "".
fs::path blocking_file(fs::path p) {
  std::error_code ec;
  for (; !p.empty(); p = p.parent_path()) {
    if (fs::is_regular_file(p, ec)) return p;
    if (p == p.parent_path()) break;
  }
  return {};
}

// What stopped the temporary file's creation, said of the folder the user named rather than of
// the temporary file: a missing folder, or a file where a folder should be.
std::string creation_step(const fs::path& path, int error) {
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (const fs::path file = blocking_file(dir); error == ENOTDIR && !file.empty())
    return fmt::format("'{}' is a file, not a folder", file.string());
  if (error == ENOENT && !fs::exists(dir, ec))
    return fmt::format("its folder '{}' does not exist", dir.string());
  return "creating a temporary file in its folder";
}

}  // namespace

std::string filesystem_error_line(const fs::filesystem_error& e) {
  // libstdc++'s what() is "filesystem error: <operation>: <reason> [path1] [path2]".
  std::string operation = e.what();
  const std::string prefix = "filesystem error: ", reason = ": " + e.code().message();
  if (operation.starts_with(prefix)) operation.erase(0, prefix.size());
  operation = operation.substr(0, operation.find(reason));
  const fs::path file =
      e.code() == std::errc::not_a_directory ? blocking_file(e.path1()) : fs::path();
  return fmt::format("'{}': {} ({})", e.path1().string(),
                     file.empty() ? e.code().message()
                                  : fmt::format("'{}' is a file, not a folder", file.string()),
                     operation);
}

void write_file_atomic(const fs::path& path, std::string_view content) {
  fs::path temp;
  const int fd = create_temporary(path, temp);
  if (fd < 0) {
    const std::error_code code = last_error();
    throw FileWriteError(code, path, creation_step(path, code.value()));
  }
  const auto fail = [&](std::error_code code, const char* step, bool open) {
    if (open) ::close(fd);
    ::unlink(temp.c_str());
    throw FileWriteError(code, path, step);
  };
  std::size_t written = 0;
  while (written < content.size()) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail(last_error(), "writing", true);
    if (n == 0) fail(std::make_error_code(std::errc::io_error), "writing", true);
    written += std::size_t(n);
  }
  if (::fsync(fd) != 0) fail(last_error(), "flushing to disk", true);
  if (::close(fd) != 0) fail(last_error(), "closing", false);
  if (::rename(temp.c_str(), path.c_str()) != 0) fail(last_error(), "renaming into place", false);
  // Make the rename itself durable (best effort: some file systems refuse directory fsync).
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
}

}  // namespace hnn::nn
