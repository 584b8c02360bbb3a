// The hnn program as a user runs it: --help everywhere, a short `hnn train`, `evaluate` and
// `rollout` on its run folder, and a quick `hnn reproduce` writing Table 1. (Bad input and its
// one-line errors are tested in tests/reliability.)

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct Result {
  int exit_code;
  std::string out;  // stdout only
};

// Runs `hnn ARGS`, stdout captured, stderr discarded.
Result hnn(const std::string& args) {
  const std::string command = std::string("'") + HNN_EXE + "' " + args + " 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return {-1, ""};
  std::string out;
  char buffer[4096];
  for (std::size_t n; (n = fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.append(buffer, n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

class TempDir {
 public:
  explicit TempDir(const std::string& name) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::path(HNN_BINARY_DIR) / "test_tmp" /
            (std::string("apps.") + info->test_suite_name() + "." + info->name() + "." + name);
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  std::string str() const { return "'" + path_.string() + "'"; }

 private:
  fs::path path_;
};

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The first JSON object in a program's output (train and evaluate print one).
json json_in(const std::string& out) {
  const std::size_t start = out.find('{'), end = out.rfind('}');
  if (start == std::string::npos || end == std::string::npos) return nullptr;
  return json::parse(out.substr(start, end - start + 1));
}

// The names under "Subcommands:" in `hnn --help`.
std::vector<std::string> subcommands(const std::string& help) {
  std::vector<std::string> names;
  bool in_section = false;
  for (const std::string& line : lines_of(help)) {
    if (line.rfind("Subcommands:", 0) == 0) {
      in_section = true;
      continue;
    }
    if (!in_section) continue;
    if (line.empty() || line[0] != ' ') break;
    std::istringstream words(line);
    std::string name;
    words >> name;
    names.push_back(name);
  }
  return names;
}

TEST(CliHelp, TopLevelListsTheSubcommands) {
  const Result r = hnn("--help");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::vector<std::string> names = subcommands(r.out);
  for (const char* want : {"train", "evaluate", "rollout", "reproduce"})
    EXPECT_NE(std::find(names.begin(), names.end(), want), names.end()) << want << "\n" << r.out;
}

TEST(CliHelp, EverySubcommandHasHelpListingItsOptions) {
  const std::vector<std::string> names = subcommands(hnn("--help").out);
  ASSERT_GE(names.size(), 4u);
  for (const std::string& name : names) {
    const Result r = hnn(name + " --help");
    EXPECT_EQ(r.exit_code, 0) << name;
    EXPECT_NE(r.out.find("Usage:"), std::string::npos) << name << "\n" << r.out;
    EXPECT_NE(r.out.find("Options:"), std::string::npos) << name << "\n" << r.out;
    EXPECT_NE(r.out.find("--help"), std::string::npos) << name << "\n" << r.out;
  }
  // The options issue 5 names, on the subcommands it names.
  const std::vector<std::pair<std::string, std::vector<std::string>>> required = {
      {"train",
       {"--model", "--steps", "--seed", "--dtype", "--threads", "--data", "--out", "--hidden"}},
      {"evaluate", {"--data"}},
      {"rollout", {"--integrator", "--dt", "--out"}},
      {"reproduce", {"--tasks", "--seeds", "--out"}}};
  for (const auto& [name, options] : required) {
    const std::string help = hnn(name + " --help").out;
    for (const std::string& option : options)
      EXPECT_NE(help.find(option), std::string::npos) << name << " " << option << "\n" << help;
  }
  // The task list names every task.
  const std::string train = hnn("train --help").out;
  for (const char* task : {"spring", "pendulum", "real-pendulum", "two-body", "three-body"})
    EXPECT_NE(train.find(task), std::string::npos) << task;
}

TEST(CliTrain, ShortRunWritesTheRunFolderAndPrintsItsMetrics) {
  TempDir dir("run");
  const Result r =
      hnn("train spring --steps 20 --hidden 16 16 --out " + dir.str() + " --quiet --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  for (const char* file : {"metrics.json", "loss_curve.csv", "rollout.csv", "params.bin"})
    EXPECT_TRUE(fs::is_regular_file(dir.path() / file)) << file;
  const json m = json::parse(read_text(dir.path() / "metrics.json"));
  EXPECT_EQ(json_in(r.out), m);  // --json: metrics.json's content, and nothing else
  EXPECT_EQ(r.out.front(), '{');
  EXPECT_EQ(m["task"], "spring");
  EXPECT_EQ(m["model"], "hnn");
  EXPECT_EQ(m["steps"], 20);
  EXPECT_EQ(m["hidden"], "16-16");
  EXPECT_EQ(m["dtype"], "double");
  EXPECT_EQ(m["threads"], 2);  // the default: both cores
  for (const char* key : {"seed", "train_loss", "train_loss_se", "test_loss", "test_loss_se",
                          "energy_mse", "energy_mse_se", "train_seconds"}) {
    ASSERT_TRUE(m.contains(key)) << key;
    EXPECT_TRUE(m[key].is_number()) << key;
  }
  EXPECT_EQ(lines_of(read_text(dir.path() / "loss_curve.csv")).at(0), "step,train_loss,test_loss");
  EXPECT_EQ(lines_of(read_text(dir.path() / "rollout.csv")).at(0),
            "source,traj,t,x_0,x_1,energy,learned_h");
}

TEST(CliTrain, OptionsReachTheRun) {
  TempDir dir("run");
  const Result r =
      hnn("train pendulum --model baseline --steps 7 --seed 3 --dtype float "
          "--hidden 8 --out " +
          dir.str() + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const json m = json::parse(read_text(dir.path() / "metrics.json"));
  EXPECT_EQ(m["model"], "baseline");
  EXPECT_EQ(m["steps"], 7);
  EXPECT_EQ(m["seed"], 3);
  EXPECT_EQ(m["dtype"], "float");
  EXPECT_EQ(m["hidden"], "8");
  EXPECT_EQ(m["n_train"], 1125);
}

TEST(CliEvaluateAndRollout, WorkOnASavedRun) {
  TempDir dir("run");
  ASSERT_EQ(hnn("train spring --steps 10 --hidden 16 16 --out " + dir.str() + " --quiet").exit_code,
            0);
  const json trained = json::parse(read_text(dir.path() / "metrics.json"));
  // evaluate: the same numbers from the saved parameters.
  const Result e = hnn("evaluate " + dir.str() + " --json");
  ASSERT_EQ(e.exit_code, 0) << e.out;
  const json evaluated = json_in(e.out);
  for (const char* key : {"train_loss", "test_loss", "energy_mse"})
    EXPECT_EQ(evaluated[key].get<double>(), trained[key].get<double>()) << key;
  // rollout with a fixed-step integrator: 2 trajectories x 50 times, true and model.
  const fs::path csv = dir.path() / "rk4.csv";
  const Result r = hnn("rollout " + dir.str() + " --integrator rk4 --dt 0.01 --points 50 " +
                       "--trajectories 2 --t-end 5 --out '" + csv.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::vector<std::string> lines = lines_of(read_text(csv));
  ASSERT_EQ(lines.size(), 1u + 2u * 2u * 50u);
  EXPECT_EQ(lines[0], "source,traj,t,x_0,x_1,energy,learned_h");
  EXPECT_EQ(lines[1].rfind("true,0,0,", 0), 0u) << lines[1];  // per trajectory: truth, model
  EXPECT_EQ(lines[51].rfind("hnn,0,0,", 0), 0u) << lines[51];
  EXPECT_NE(lines[100].find(",5,"), std::string::npos) << lines[100];  // t_end of trajectory 0
  EXPECT_NE(r.out.find("hnn rollout: 2 trajectories, rk4 -> "), std::string::npos) << r.out;
}

// Without --json, a few lines a person reads: the run, its losses with standard errors and R²,
// its rollouts beside the truth's, the energy error absolute and relative, the time, the files.
TEST(CliTrain, PrintsASummaryNotTheJson) {
  TempDir dir("run");
  const Result r = hnn("train spring --steps 20 --hidden 16 16 --out " + dir.str() + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(r.out.find('{'), std::string::npos) << r.out;
  EXPECT_LE(lines_of(r.out).size(), 8u) << r.out;
  const json m = json::parse(read_text(dir.path() / "metrics.json"));
  for (const std::string& want :
       {std::string("spring hnn: seed 0, 20 steps, hidden 16-16, double"),
        fmt::format("test {:.3g} ± {:.2g}", m["test_loss"].get<double>(),
                    m["test_loss_se"].get<double>()),
        fmt::format("R² test {:.4g}", m["test_r2"].get<double>()),
        std::string("valid prediction time"), std::string("the truth perturbed by 1e-4"),
        fmt::format("MSE {:.3g} ± {:.2g} against the true H", m["energy_mse"].get<double>(),
                    m["energy_mse_se"].get<double>()),
        fmt::format("relative {:.3g}", m["energy_relative_mse"].get<double>()),
        std::string("training "), std::string(", loss curve "),
        std::string("metrics.json, params.bin, rollout.csv")}) {
    EXPECT_NE(r.out.find(want), std::string::npos) << want << " is not in:\n" << r.out;
  }
  // evaluate says what it did: which parameters, on which data, what it wrote.
  const Result e = hnn("evaluate " + dir.str());
  ASSERT_EQ(e.exit_code, 0) << e.out;
  EXPECT_EQ(e.out.find('{'), std::string::npos) << e.out;
  EXPECT_NE(e.out.find("hnn evaluate: the parameters in " + (dir.path() / "params.bin").string() +
                       " on its own data (the task's, seed 0)"),
            std::string::npos)
      << e.out;
  EXPECT_NE(e.out.find("wrote      nothing"), std::string::npos) << e.out;
  const Result written = hnn("evaluate " + dir.str() + " --write");
  EXPECT_NE(written.out.find("wrote      rollout.csv"), std::string::npos) << written.out;
}

TEST(CliHelp, HasNoTypeTagsAndStatesDefaultsAndFormats) {
  const std::regex tag(
      R"(\b(INT|UINT|UINT64|FLOAT|BOOLEAN)\b|:\{|:(POSITIVE|NONNEGATIVE|DIR|FILE)\b)");
  for (const std::string& name : subcommands(hnn("--help").out)) {
    const std::string help = hnn(name + " --help").out;
    std::smatch m;
    EXPECT_FALSE(std::regex_search(help, m, tag)) << name << ": '" << m.str() << "' in\n" << help;
  }
  const std::string train = hnn("train --help").out;
  for (const char* want : {"--steps N", "--seed N", "(default: 0)",
                           "(default: each task's own: 2000 (spring", "150000 (double-pendulum)",
                           "auto (the default: by trajectories when the file has more "
                           "than one, else by time)"}) {
    EXPECT_NE(train.find(want), std::string::npos) << want << " is not in\n" << train;
  }
  EXPECT_NE(hnn("simulate --help").out.find("--energy LO:HI"), std::string::npos);
  const Result version = hnn("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_TRUE(std::regex_match(version.out, std::regex("hnn [0-9]+\\.[0-9]+\\.[0-9]+\n")))
      << version.out;
}

// The integrators --help lists are those an unknown one's error lists.
TEST(CliHelp, ListsTheIntegratorsTheErrorsList) {
  TempDir dir("simulate");
  const std::string command = "'" + std::string(HNN_EXE) +
                              "' simulate --hamiltonian 'p^2/2 + q^2/2' --coords q --momenta p "
                              "--trajectories 1 --t-end 1 --points 2 --integrator foo --out " +
                              dir.str() + "/x.csv 2>&1";  // the error, on stderr
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char buffer[4096];
  const std::size_t n = fread(buffer, 1, sizeof buffer, pipe);
  pclose(pipe);
  const std::string error(buffer, n);
  const std::size_t known = error.find("known: ");
  ASSERT_NE(known, std::string::npos) << error;
  const std::string list = error.substr(known + 7, error.find('\n') - known - 7);
  for (const char* name : {"simulate", "rollout"}) {
    const std::string help = hnn(std::string(name) + " --help").out;
    EXPECT_NE(help.find("One of " + list), std::string::npos) << list << " is not in\n" << help;
  }
}

TEST(CliReproduce, WritesTable1WithThePapersValues) {
  TempDir dir("results");
  // The reversibility report (seconds per spring model) is covered by tasks.Reproduce.*.
  const Result r = hnn(
      "reproduce --tasks spring,real-pendulum --steps 20 --no-reversibility --out " + dir.str());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  ASSERT_TRUE(fs::is_regular_file(dir.path() / "table1.md"));
  ASSERT_TRUE(fs::is_regular_file(dir.path() / "table1.json"));
  const json table = json::parse(read_text(dir.path() / "table1.json"));
  ASSERT_TRUE(table.is_array());
  ASSERT_EQ(table.size(), 4u);  // 2 tasks x {baseline, hnn}
  std::vector<std::string> seen;
  for (const json& row : table) {
    seen.push_back(row["task"].get<std::string>() + "/" + row["model"].get<std::string>());
    EXPECT_EQ(row["steps"], 20);
    for (const char* key :
         {"train_loss", "train_loss_se", "test_loss", "test_loss_se", "energy_mse", "energy_mse_se",
          "train_seconds", "paper_train_loss", "paper_test_loss", "paper_energy_mse"}) {
      ASSERT_TRUE(row.contains(key)) << key;
      EXPECT_TRUE(row[key].is_number()) << key << " = " << row[key].dump();
    }
    EXPECT_TRUE(fs::is_regular_file(dir.path() / row["task"].get<std::string>() /
                                    row["model"].get<std::string>() / "metrics.json"));
  }
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, (std::vector<std::string>{"real-pendulum/baseline", "real-pendulum/hnn",
                                            "spring/baseline", "spring/hnn"}));
  const std::string md = read_text(dir.path() / "table1.md");
  EXPECT_NE(md.find("| spring |"), std::string::npos) << md;
  EXPECT_NE(md.find("| real-pendulum |"), std::string::npos) << md;
  EXPECT_NE(md.find("3.8416e-04"), std::string::npos) << md;  // the paper's spring HNN energy
  EXPECT_NE(md.find("*paper*"), std::string::npos) << md;
  EXPECT_FALSE(fs::exists(dir.path() / "reversibility.md"));
}

}  // namespace
