#pragma once
// Helpers of the reliability tests: running the hnn program as a child process (to read its
// exit status and stderr, or to signal it), temporary folders, and file reading and writing.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace hnn::reliability {

namespace fs = std::filesystem;

/// A fresh folder, removed at the end of its scope: named after the running test (tests run in
/// parallel), or after `name` and the process (a folder shared by the tests of one process).
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    make(std::string(info->test_suite_name()) + "." + info->name());
  }
  explicit TempDir(const std::string& name) { make(name + "." + std::to_string(::getpid())); }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& leaf) const { return path_ / leaf; }

 private:
  void make(const std::string& leaf) {
    path_ = fs::path(HNN_BINARY_DIR) / "test_tmp" / "reliability" / leaf;
    fs::remove_all(path_);
    fs::create_directories(path_);
  }

  fs::path path_;
};

inline std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_text(const fs::path& path, const std::string& content) {
  std::ofstream(path, std::ios::binary) << content;
}

inline nlohmann::json read_json(const fs::path& path) {
  return nlohmann::json::parse(read_text(path));
}

/// A child hnn process; stdout and stderr go to files in `dir`; it works in `cwd` when given.
class Child {
 public:
  Child(const std::vector<std::string>& args, const fs::path& dir, const fs::path& cwd = {})
      : out_(dir / "child.out"), err_(dir / "child.err"), args_(args) {
    args_.insert(args_.begin(), HNN_EXE);
    std::vector<char*> argv;  // built before fork: the child only opens, dups and execs
    for (std::string& a : args_) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_ = ::fork();
    if (pid_ == 0) {
      const int out = ::open(out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int err = ::open(err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(out, 1);
      ::dup2(err, 2);
      if (!cwd.empty() && ::chdir(cwd.c_str()) != 0) ::_exit(126);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
  }
  ~Child() {
    if (pid_ > 0 && !waited_) {
      ::kill(pid_, SIGKILL);
      wait();
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  pid_t pid() const { return pid_; }
  void signal(int sig) const { ::kill(pid_, sig); }
  /// Waits for the end; returns the raw wait status.
  int wait() {
    if (!waited_) {
      while (::waitpid(pid_, &status_, 0) < 0 && errno == EINTR) {
      }
      waited_ = true;
    }
    return status_;
  }
  std::string out() const { return read_text(out_); }
  std::string err() const { return read_text(err_); }

 private:
  fs::path out_, err_;
  std::vector<std::string> args_;
  pid_t pid_ = -1;
  int status_ = 0;
  bool waited_ = false;
};

/// A finished hnn run: exit code (or 128 + signal), stdout and stderr.
struct Result {
  int code = -1;
  std::string out, err;
};

/// Runs hnn with `args` to the end, working files in `dir`; in the working folder `cwd` if given.
inline Result run_hnn(const std::vector<std::string>& args, const fs::path& dir,
                      const fs::path& cwd = {}) {
  Child child(args, dir, cwd);
  const int status = child.wait();
  Result r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = child.out();
  r.err = child.err();
  return r;
}

/// Polls `done` every 10 ms for up to `seconds`; true once it holds.
template <typename F>
bool wait_until(F done, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

/// A bad command and its whole one error line.
struct BadOption {
  std::vector<std::string> args;  // after `hnn`; a train run's --out is appended
  std::string message;            // the whole line after "hnn: error: "
};

/// A bad `hnn train` and how its one error line starts.
struct BadTrain {
  std::vector<std::string> args;  // after `hnn`
  std::string message;            // the start of the line after "hnn: error: "
};

/// A bad command: exit 1, its one line on stderr (CLI11's own parse errors end with a pointer to
/// --help), nothing on stdout.
inline void expect_one_line_error(const Result& r, const std::string& message,
                                  const std::string& what) {
  EXPECT_EQ(r.code, 1) << what;
  const std::string line = "hnn: error: " + message;
  EXPECT_TRUE(r.err == line + "\n" || r.err == line + " (see --help)\n")
      << what << "\n  got:    " << r.err << "  wanted: " << line;
  EXPECT_EQ(r.out, "") << what;
}

/// Each bad `hnn train` command, run with --quiet --out DIR/run: its one line, and no run folder.
inline void expect_refused_with_no_run_folder(const std::vector<BadOption>& cases) {
  const TempDir dir;
  for (const BadOption& bad : cases) {
    std::vector<std::string> args = bad.args;
    const fs::path out = dir / "run";
    args.insert(args.end(), {"--quiet", "--out", out.string()});
    std::string what;
    for (const std::string& a : bad.args) what += a + " ";
    expect_one_line_error(run_hnn(args, dir.path()), bad.message, what);
    EXPECT_FALSE(fs::exists(out)) << what;
  }
}

inline std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

/// A bad command: exit 1, and one line on stderr that starts with "hnn: error: " + `start`.
inline void expect_one_line_error_starting(const Result& r, const std::string& start,
                                           const std::string& what) {
  EXPECT_EQ(r.code, 1) << what;
  EXPECT_TRUE(r.err.starts_with("hnn: error: " + start)) << what << "\n  got: " << r.err;
  EXPECT_EQ(lines(r.err).size(), 1u) << what << "\n  got: " << r.err;
}

/// The shipped real-pendulum data file.
inline fs::path shipped_pendulum_data() {
  return fs::path(HNN_SOURCE_DIR) / "data" / "lipson" / "real_pend_h_1.txt";
}

/// A pendulum's trajectories with exact dx/dt, written by `hnn simulate` into dir/pend.csv (10
/// trajectories of 15 points): the data task's test file. Returns its path.
inline std::string simulated_pendulum_csv(const fs::path& dir) {
  const std::string csv = (dir / "pend.csv").string();
  const Result r =
      run_hnn({"simulate", "--hamiltonian", "p^2/2 + 2*(1 - cos(q))", "--coords", "q", "--momenta",
               "p", "--trajectories", "10", "--t-end", "2", "--points", "15", "--out", csv},
              dir);
  EXPECT_EQ(r.code, 0) << r.err;
  return csv;
}

/// metrics.json without the keys that measure time (the only ones two runs may differ in).
inline nlohmann::json without_timings(nlohmann::json metrics) {
  for (const char* key : {"train_seconds", "curve_seconds", "eval_seconds", "data_seconds"})
    metrics.erase(key);
  return metrics;
}

}  // namespace hnn::reliability
