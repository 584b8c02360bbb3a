// A checked plan run through the sweep engine: takes the folder's lock, copies this program,
// writes DIR/plan.json, then becomes the Python driver (apps/hnn/sweep/sweep_driver.py) that runs
// the plan through Dask distributed. `hnn sweep` and `hnn compare` both end here.

#include "apps/hnn/sweep/launch.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "apps/hnn/commands/validators.h"
#include "nn/atomic_file.h"

namespace hnn::app::sweep {

void add_launch_options(CLI::App& cmd, LaunchOptions& o) {
  cmd.add_option("--scheduler", o.scheduler,
                 "A running Dask scheduler, tcp://HOST:PORT, whose workers share --out "
                 "(default: a local cluster)");
  cmd.add_option("--workers", o.workers,
                 "Local cluster's workers (default: the cores / --threads-per-run)")
      ->check(integer_in(1, 1024));
  cmd.add_option("--threads-per-run", o.threads_per_run, "hnn train --threads of every run")
      ->check(integer_in(1, 256))
      ->capture_default_str();
  cmd.add_flag("--retry-failed", o.retry_failed,
               "Run again the runs that failed for their own reasons (default: report them)");
}

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path own_executable() { return fs::read_symlink("/proc/self/exe"); }

std::string host_name() {
  char name[256] = {};
  ::gethostname(name, sizeof(name) - 1);
  return name;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  return text;
}

// DIR/sweep.lock, held (flock) by this process and, after exec, by the driver until it exits: a
// killed sweep leaves no stale lock. The file says who holds it, for the refusal's message.
int take_lock(const fs::path& dir) {
  const fs::path file = dir / "sweep.lock";
  const int fd = ::open(file.c_str(), O_RDWR | O_CREAT, 0644);  // no O_CLOEXEC: kept across exec
  if (fd < 0) {
    throw std::invalid_argument(
        fmt::format("cannot open the sweep lock '{}': {}", file.string(), std::strerror(errno)));
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    std::ifstream in(file);
    std::string holder;
    std::getline(in, holder);
    ::close(fd);
    throw std::invalid_argument(fmt::format(
        "sweep folder '{}' is in use by another sweep ({}; lock {}): wait for it to finish, or "
        "give another --out",
        dir.string(), holder.empty() ? "holder unknown" : holder, file.string()));
  }
  const std::string holder =
      fmt::format("pid {} on host {} since {}\n", ::getpid(), host_name(), utc_now());
  if (::ftruncate(fd, 0) != 0 || ::write(fd, holder.data(), holder.size()) < 0) {
    throw std::invalid_argument(
        fmt::format("cannot write the sweep lock '{}': {}", file.string(), std::strerror(errno)));
  }
  return fd;
}

std::string file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// DIR/hnn: this program, copied (when it differs) so that rebuilding the tree during a sweep does
// not change what its runs execute, and so that workers sharing DIR find it there.
fs::path install_program(const fs::path& dir) {
  const fs::path self = own_executable(), copy = dir / "hnn";
  if (fs::exists(copy) && fs::file_size(copy) == fs::file_size(self) &&
      file_bytes(copy) == file_bytes(self)) {
    return copy;
  }
  const fs::path tmp = dir / ".hnn.tmp";
  fs::copy_file(self, tmp, fs::copy_options::overwrite_existing);
  fs::permissions(tmp, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                           fs::perms::others_read | fs::perms::others_exec);
  fs::rename(tmp, copy);  // a run still executing the old copy keeps its inode
  return copy;
}

json plan_json(const SweepPlan& plan, const LaunchOptions& o, const fs::path& out,
               const std::string& spec, const fs::path& program) {
  json runs = json::array();
  for (const SweepRun& r : plan.runs) {
    runs.push_back({{"name", r.name},
                    {"values", json::parse(r.values.dump())},
                    {"args", r.args},
                    {"settings", r.settings}});
  }
  return {{"spec", spec},
          {"out", out.string()},
          {"hnn", program.string()},
          {"created", utc_now()},
          {"options",
           {{"scheduler", o.scheduler},
            {"workers", o.workers},
            {"threads_per_run", o.threads_per_run},
            {"retry_failed", o.retry_failed}}},
          {"keys", plan.keys},
          {"charts", plan.charts},
          {"runs", runs}};
}

[[noreturn]] void become_driver(const std::string& mode, const fs::path& plan_file) {
  const char* env_python = std::getenv("HNN_PYTHON");
  const std::string python = env_python ? env_python : "/usr/bin/python3";
  const std::string driver =
      shared_file("HNN_SWEEP_DRIVER", "sweep_driver.py", HNN_SWEEP_DRIVER_SOURCE).string();
  std::fflush(nullptr);
  std::vector<std::string> args = {python, driver, mode, plan_file.string()};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execv(python.c_str(), argv.data());
  throw std::invalid_argument(fmt::format("cannot start the sweep driver ({} {}): {}", python,
                                          driver, std::strerror(errno)));
}

}  // namespace

std::string shell_quote(const std::string& text) {
  const bool plain = !text.empty() && text.find_first_not_of(
                                          "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                          "0123456789_./=+,:@%-") == std::string::npos;
  if (plain) return text;
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

void list_runs(const SweepPlan& plan, const LaunchOptions& o, const fs::path& out) {
  for (const SweepRun& r : plan.runs) {
    std::string line = "hnn train";
    for (const std::string& a : r.args) line += " " + shell_quote(a);
    line += fmt::format(" --threads {} --quiet --out {}", o.threads_per_run,
                        shell_quote((out / "runs" / r.name).string()));
    fmt::print("{}\n", line);
  }
}

fs::path shared_file(const char* env, const std::string& name, const fs::path& source) {
  if (const char* path = std::getenv(env)) return path;
  const fs::path installed = own_executable().parent_path().parent_path() / "share" / "hnn" / name;
  if (fs::exists(installed)) return installed;
  return source;
}

void check_scheduler(const std::string& scheduler) {
  if (!scheduler.empty() && scheduler.find("://") == std::string::npos) {
    throw std::invalid_argument(
        fmt::format("--scheduler expects a Dask scheduler's address like tcp://HOST:8786, got '{}'",
                    scheduler));
  }
}

void launch(const SweepPlan& plan, const LaunchOptions& o, const fs::path& out,
            const std::string& spec, const std::string& mode, const json& extra) {
  if (fs::exists(out) && !fs::is_directory(out))
    throw std::invalid_argument(fmt::format("--out '{}' is a file, not a folder", out.string()));
  fs::create_directories(out);
  take_lock(out);  // held until the driver exits
  const fs::path program = install_program(out);
  const fs::path plan_file = out / "plan.json";
  json document = plan_json(plan, o, out, spec, program);
  if (extra.is_object()) document.update(extra);
  nn::write_file_atomic(plan_file, document.dump(1) + "\n");
  become_driver(mode, plan_file);
}

}  // namespace hnn::app::sweep
