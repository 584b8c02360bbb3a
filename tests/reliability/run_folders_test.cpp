// docs/inputs.md, "Run folders": a run finds its data file from any working folder (its
// absolute path and SHA-256 are recorded), `--data` points at a moved file and another file is
// refused; `hnn train` replaces an existing run only with --force, leaving none of its files.

#include <gtest/gtest.h>

#include <cctype>

#include "reliability_util.h"
#include "tasks/data/file_digest.h"
#include "tasks/error.h"

namespace hnn::reliability {
namespace {

// A pendulum simulated into DIR/pend.csv, trained as a data run into DIR/run from DIR (the
// data given by a relative path), once per process; each test works on a copy.
class RunsTravel : public ::testing::Test {
 protected:
  // Once per process, in SetUp (not SetUpTestSuite, whose failures ctest reports as skips).
  void SetUp() override {
    if (made_) return;
    made_ = new TempDir("RunsTravel.made");
    const fs::path dir = made_->path();
    const Result simulated = run_hnn(
        {"simulate", "--hamiltonian", "p^2/2 + 2*(1 - cos(q))", "--coords", "q", "--momenta", "p",
         "--trajectories", "10", "--t-end", "2", "--points", "15", "--out", "pend.csv"},
        dir, dir);
    ASSERT_EQ(simulated.code, 0) << simulated.err;
    const Result trained =
        run_hnn({"train", "data", "--data", "pend.csv", "--coords", "q", "--momenta", "p",
                 "--steps", "10", "--hidden", "8", "--quiet", "--out", "run"},
                dir, dir);
    ASSERT_EQ(trained.code, 0) << trained.err;
  }
  static void TearDownTestSuite() {
    delete made_;
    made_ = nullptr;
  }

  // The run and its data copied into this test's folder: DIR/run and DIR/pend.csv.
  fs::path copy() {
    fs::copy(*made_ / "run", dir_ / "run", fs::copy_options::recursive);
    fs::copy_file(*made_ / "pend.csv", dir_ / "pend.csv");
    // Where the copy's data are, for evaluate and for --resume.
    nlohmann::json m = read_json(dir_ / "run" / "metrics.json");
    m["data_file"] = (dir_ / "pend.csv").string();
    write_text(dir_ / "run" / "metrics.json", m.dump(2));
    nlohmann::json state = read_json(dir_ / "run" / "checkpoint" / "state.json");
    state["run"]["data_file"] = m["data_file"];
    write_text(dir_ / "run" / "checkpoint" / "state.json", state.dump());
    return dir_ / "run";
  }

  // hnn `args` from the root folder: no path in them can resolve against the working folder.
  Result from_root(const std::vector<std::string>& args) { return run_hnn(args, dir_.path(), "/"); }

  static TempDir* made_;
  TempDir dir_;
};
TempDir* RunsTravel::made_ = nullptr;

TEST(FileDigest, IsTheSha256OfTheBytes) {
  const TempDir dir;
  write_text(dir / "abc", "abc");
  EXPECT_EQ(tasks::file_sha256(dir / "abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_THROW(tasks::file_sha256(dir / "absent"), tasks::Error);
  EXPECT_THROW(tasks::file_sha256(dir.path()), tasks::Error);
}

TEST_F(RunsTravel, TheDataFileIsRecordedByAbsolutePathAndChecksum) {
  const nlohmann::json m = read_json(*made_ / "run" / "metrics.json");
  EXPECT_EQ(m["data_file"], (*made_ / "pend.csv").string());
  EXPECT_EQ(m["data_sha256"], tasks::file_sha256(*made_ / "pend.csv"));
  // The checkpoint holds them too (for --resume).
  const nlohmann::json state = read_json(*made_ / "run" / "checkpoint" / "state.json");
  EXPECT_EQ(state["run"]["data_file"], m["data_file"]);
  EXPECT_EQ(state["run"]["data_sha256"], m["data_sha256"]);
}

// The run as trained, from "/" (it read its data as "pend.csv" from its own folder).
TEST_F(RunsTravel, ExportEvaluateAndRolloutWorkFromAnyFolder) {
  const fs::path run = *made_ / "run";
  const Result exported =
      from_root({"export", run.string(), "--format", "json", "--out", (dir_ / "h.json").string()});
  EXPECT_EQ(exported.code, 0) << exported.err;
  const Result evaluated = from_root({"evaluate", run.string()});
  EXPECT_EQ(evaluated.code, 0) << evaluated.err;
  const Result rolled = from_root({"rollout", run.string(), "--out", (dir_ / "r.csv").string()});
  EXPECT_EQ(rolled.code, 0) << rolled.err;
}

TEST_F(RunsTravel, AMovedDataFileIsFoundWithDataAndAnotherFileIsRefused) {
  const fs::path run = copy(), data = dir_ / "pend.csv", moved = dir_ / "moved.csv";
  ASSERT_EQ(
      from_root({"export", run.string(), "--format", "c", "--out", (dir_ / "a.c").string()}).code,
      0);
  fs::rename(data, moved);
  const std::string missing = fmt::format(
      "hnn: error: the data file '{}' of run '{}' is missing (moved?): give its place with "
      "--data FILE\n",
      data.string(), run.string());
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"evaluate", run.string()},
        {"export", run.string(), "--format", "c", "--out", (dir_ / "b.c").string()},
        {"reversibility", run.string(), "--trajectories", "2"},
        {"train", "--resume", run.string(), "--quiet"}}) {
    const Result r = from_root(args);
    EXPECT_EQ(r.code, 1) << args[0];
    EXPECT_EQ(r.err, missing) << args[0];
  }
  const Result exported = from_root({"export", run.string(), "--format", "c", "--out",
                                     (dir_ / "b.c").string(), "--data", moved.string()});
  ASSERT_EQ(exported.code, 0) << exported.err;
  EXPECT_EQ(read_text(dir_ / "b.c"), read_text(dir_ / "a.c"));
  EXPECT_EQ(from_root({"evaluate", run.string(), "--data", moved.string()}).code, 0);
  const Result reversed =
      from_root({"reversibility", run.string(), "--trajectories", "2", "--data", moved.string()});
  EXPECT_EQ(reversed.code, 0) << reversed.err;
  EXPECT_TRUE(fs::exists(run / "reversibility.json"));
  const Result two =
      from_root({"reversibility", run.string(), run.string(), "--data", moved.string()});
  EXPECT_EQ(two.code, 1);
  EXPECT_NE(two.err.find("names the data file of one run folder"), std::string::npos) << two.err;

  // Another file in its place: the last digit of the first row changed.
  std::string text = read_text(moved);
  const std::size_t digit = text.find('\n', text.find('\n') + 1) - 1;
  ASSERT_TRUE(std::isdigit(text[digit])) << text.substr(0, digit + 1);
  text[digit] = text[digit] == '9' ? '8' : char(text[digit] + 1);
  write_text(moved, text);
  const Result other = from_root({"export", run.string(), "--format", "c", "--out",
                                  (dir_ / "c.c").string(), "--data", moved.string()});
  EXPECT_EQ(other.code, 1);
  EXPECT_EQ(other.err,
            fmt::format("hnn: error: '{}' is not the data file of run '{}' (its "
                        "SHA-256 is {}..., the run's {}...): give the run's own file "
                        "with --data FILE\n",
                        moved.string(), run.string(), tasks::file_sha256(moved).substr(0, 12),
                        tasks::file_sha256(*made_ / "pend.csv").substr(0, 12)));
  EXPECT_FALSE(fs::exists(dir_ / "c.c"));
  // At the recorded place too; `hnn evaluate --data` evaluates on another file by design.
  fs::copy_file(moved, data);
  EXPECT_EQ(from_root({"evaluate", run.string()}).code, 1);
  const Result elsewhere = from_root({"evaluate", run.string(), "--data", moved.string()});
  EXPECT_EQ(elsewhere.code, 0) << elsewhere.err;
}

// Runs written before the checksum (none in metrics.json, a path relative to where they were
// trained) still load, from that folder.
TEST_F(RunsTravel, RunsWithoutAChecksumStillLoad) {
  const fs::path run = copy();
  nlohmann::json m = read_json(run / "metrics.json");
  m.erase("data_sha256");
  m["data_file"] = "pend.csv";
  write_text(run / "metrics.json", m.dump(2));
  const Result r = run_hnn({"evaluate", run.string()}, dir_.path(), dir_.path());
  EXPECT_EQ(r.code, 0) << r.err;
}

// A moved data file given to --resume: the run goes on (here, continued to more steps).
TEST_F(RunsTravel, ResumeTakesTheMovedDataFile) {
  const fs::path run = copy();
  fs::rename(dir_ / "pend.csv", dir_ / "moved.csv");
  const Result r = from_root({"train", "--resume", run.string(), "--data",
                              (dir_ / "moved.csv").string(), "--steps", "12", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json m = read_json(run / "metrics.json");
  EXPECT_EQ(m["data_file"], (dir_ / "moved.csv").string());
  EXPECT_EQ(m["steps"], 12);
}

// ---- no silent overwrite --------------------------------------------------------------------

std::vector<std::string> small_spring(const fs::path& out, const std::string& steps = "5") {
  return {"train", "spring", "--steps", steps, "--hidden", "8", "--quiet", "--out", out.string()};
}

std::vector<std::string> plus(std::vector<std::string> args, const std::string& extra) {
  args.push_back(extra);
  return args;
}

TEST(RunFolderOverwrite, AFolderHoldingARunIsReplacedOnlyWithForce) {
  const TempDir dir;
  const fs::path run = dir / "run";
  ASSERT_EQ(run_hnn(small_spring(run), dir.path()).code, 0);
  write_text(run / "rollout_dopri5.csv", "stale\n");  // another system's, say
  const std::string params = read_text(run / "params.bin");
  const Result again = run_hnn(small_spring(run, "6"), dir.path());
  EXPECT_EQ(again.code, 1);
  EXPECT_EQ(again.err, fmt::format("hnn: error: '{}' already holds a run: replace it with --force "
                                   "(its files are removed), or choose another --out\n",
                                   run.string()));
  EXPECT_EQ(read_text(run / "params.bin"), params);
  // Bad data with --force: refused before anything is removed.
  const Result bad = run_hnn({"train", "real-pendulum", "--data", (dir / "none.txt").string(),
                              "--force", "--quiet", "--out", run.string()},
                             dir.path());
  EXPECT_EQ(bad.code, 1);
  EXPECT_TRUE(fs::exists(run / "rollout_dopri5.csv"));
  EXPECT_EQ(read_text(run / "params.bin"), params);
  const Result forced = run_hnn(plus(small_spring(run, "6"), "--force"), dir.path());
  ASSERT_EQ(forced.code, 0) << forced.err;
  EXPECT_FALSE(fs::exists(run / "rollout_dopri5.csv"));
  EXPECT_EQ(read_json(run / "metrics.json")["steps"], 6);
  EXPECT_EQ(read_json(run / "checkpoint" / "state.json")["total_steps"], 6);
}

TEST(RunFolderOverwrite, AFolderOfOtherFilesIsRefusedEvenWithForce) {
  const TempDir dir;
  const fs::path mine = dir / "mine";
  fs::create_directories(mine);
  write_text(mine / "notes.txt", "mine\n");
  for (const bool force : {false, true}) {
    const std::vector<std::string> args = small_spring(mine);
    const Result r = run_hnn(force ? plus(args, "--force") : args, dir.path());
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(r.err, fmt::format("hnn: error: '{}' is not empty and holds no run ('notes.txt'){}: "
                                 "choose another --out\n",
                                 mine.string(), force ? ", so --force does not clear it" : ""));
    EXPECT_EQ(read_text(mine / "notes.txt"), "mine\n");
  }
  // An empty folder, or one a run killed before its first checkpoint left: taken as it is.
  fs::create_directories(dir / "empty");
  EXPECT_EQ(run_hnn(small_spring(dir / "empty"), dir.path()).code, 0);
  fs::create_directories(dir / "killed" / "checkpoint");
  write_text(dir / "killed" / "checkpoint" / "step-000000001.bin", "");
  EXPECT_EQ(run_hnn(small_spring(dir / "killed"), dir.path()).code, 0);
  const Result resumed =
      run_hnn({"train", "--resume", (dir / "empty").string(), "--force"}, dir.path());
  EXPECT_EQ(resumed.code, 1);
  EXPECT_EQ(resumed.err,
            "hnn: error: --force cannot be combined with --resume: a resumed run keeps its own "
            "settings\n");
}

// Without --out, a data run's folder is named after its data file: two files, two folders.
TEST(RunFolderOverwrite, DataRunsDefaultToAFolderPerDataFile) {
  const TempDir dir;
  for (const char* name : {"a.csv", "b.csv"}) {
    ASSERT_EQ(run_hnn({"simulate", "--hamiltonian", "p^2/2 + q^2/2", "--coords", "q", "--momenta",
                       "p", "--trajectories", "6", "--t-end", "2", "--points", "10", "--out", name},
                      dir.path(), dir.path())
                  .code,
              0);
    const Result r = run_hnn({"train", "data", "--data", name, "--coords", "q", "--momenta", "p",
                              "--steps", "3", "--hidden", "4", "--quiet"},
                             dir.path(), dir.path());
    ASSERT_EQ(r.code, 0) << r.err;
  }
  EXPECT_TRUE(fs::exists(dir / "runs" / "data" / "a" / "hnn" / "metrics.json"));
  EXPECT_TRUE(fs::exists(dir / "runs" / "data" / "b" / "hnn" / "metrics.json"));
}

}  // namespace
}  // namespace hnn::reliability
