// Scattered states through the program: `hnn simulate --scattered` writes states with exact dx/dt
// and no time column, `hnn train data` learns from them and is judged on held-out points (no
// rollouts, said in metrics.json and the summary), and the refusals around them: one line
// "hnn: error: ...", exit 1, nothing written.

#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include "physics/expression_system.h"
#include "reliability_util.h"

namespace hnn::reliability {
namespace {

const char* const kHenonHeiles = "(px^2+py^2)/2 + (x^2+y^2)/2 + x^2*y - y^3/3";

std::vector<std::string> scattered_args(const fs::path& out, const std::string& n = "120") {
  return {"simulate",
          "--hamiltonian",
          kHenonHeiles,
          "--coords",
          "x,y",
          "--momenta",
          "px,py",
          "--scattered",
          n,
          "--sample",
          "x=-2:2,y=-2:2,px=-1:1,py=-1:1",
          "--seed",
          "4",
          "--out",
          out.string()};
}

physics::Batch csv_columns(const std::vector<std::string>& rows, int first, int count) {
  physics::Batch x(Eigen::Index(rows.size()) - 1, count);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    std::stringstream in(rows[std::size_t(i) + 1]);
    std::vector<double> cells;
    for (std::string cell; std::getline(in, cell, ',');) cells.push_back(std::stod(cell));
    for (int j = 0; j < count; ++j) x(i, j) = cells[std::size_t(first + j)];
  }
  return x;
}

TEST(ScatteredCli, SimulateWritesStatesWithExactDerivativesAndNoTime) {
  const TempDir dir;
  const Result r = run_hnn(scattered_args(dir / "hh.csv"), dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("120 scattered states"), std::string::npos) << r.out;
  const std::vector<std::string> rows = lines(read_text(dir / "hh.csv"));
  ASSERT_EQ(rows.size(), 121u);
  EXPECT_EQ(rows[0], "x,y,px,py,dx/dt,dy/dt,dpx/dt,dpy/dt");
  const physics::Batch x = csv_columns(rows, 0, 4);
  EXPECT_LE(x.leftCols(2).cwiseAbs().maxCoeff(), 2.0);
  EXPECT_LE(x.rightCols(2).cwiseAbs().maxCoeff(), 1.0);
  EXPECT_GT(x.leftCols(2).cwiseAbs().maxCoeff(), 1.5);
  const physics::ExpressionSystem hh(kHenonHeiles, {"x", "y"}, {"px", "py"});
  physics::Batch field;
  hh.vector_field(x, field);
  EXPECT_LT((csv_columns(rows, 4, 4) - field).cwiseAbs().maxCoeff(), 1e-14);
  // The states come from the seed alone, bit for bit. (The derivatives' last bits may not:
  // GiNaC may order the terms of a derivative differently from one process to the next.)
  ASSERT_EQ(run_hnn(scattered_args(dir / "again.csv"), dir.path()).code, 0);
  EXPECT_EQ(csv_columns(lines(read_text(dir / "again.csv")), 0, 4), x);
}

TEST(ScatteredCli, TheDataTaskLearnsScatteredStatesJudgedOnHeldOutPoints) {
  const TempDir dir;
  const fs::path csv = dir / "hh.csv", run = dir / "run";
  ASSERT_EQ(run_hnn(scattered_args(csv), dir.path()).code, 0);
  const std::vector<std::string> train = {"train",         "data",       "--data",    csv.string(),
                                          "--coords",      "x,y",        "--momenta", "px,py",
                                          "--steps",       "20",         "--hidden",  "8",
                                          "--hamiltonian", kHenonHeiles, "--out",     run.string()};
  const Result r = run_hnn(train, dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json m = read_json(run / "metrics.json");
  EXPECT_EQ(m["n_train"], 96);  // the last fifth of the rows are the test set
  EXPECT_EQ(m["n_test"], 24);
  ASSERT_TRUE(m["hamiltonian_rel_l2"].is_number()) << m.dump();
  EXPECT_EQ(m["hamiltonian_rel_l2_count"], 24);
  EXPECT_TRUE(m["test_r2"].is_number());
  EXPECT_TRUE(m["rollouts_skipped"].is_string());
  for (const char* absent : {"valid_prediction_time", "energy_mse", "coordinate_mse"})
    EXPECT_FALSE(m.contains(absent)) << absent;
  EXPECT_FALSE(fs::exists(run / "rollout.csv"));
  EXPECT_NE(m["data"].get<std::string>().find("scattered states (no time column)"),
            std::string::npos);
  // The summary says there are no rollouts and gives the H error, and no rollout figures.
  EXPECT_NE(r.out.find("rollouts   none: scattered states"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("H          relative L2 error"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("rollouts   valid prediction time"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("energy     MSE"), std::string::npos) << r.out;

  // Rollouts on request: from the test states, over a span given (there is none to default to).
  const Result no_span = run_hnn({"rollout", run.string()}, dir.path());
  EXPECT_EQ(no_span.code, 1);
  EXPECT_NE(no_span.err.find("have no time span to roll out over: give one with --t-end"),
            std::string::npos)
      << no_span.err;
  const Result rolled = run_hnn({"rollout", run.string(), "--t-end", "0.5"}, dir.path());
  EXPECT_EQ(rolled.code, 0) << rolled.err;
}

struct BadScattered {
  std::vector<std::string> args;
  std::string message;
};

TEST(ScatteredCli, RefusalsAreOneLineAndWriteNothing) {
  const TempDir dir;
  const fs::path csv = dir / "hh.csv", out = dir / "out";
  ASSERT_EQ(run_hnn(scattered_args(csv), dir.path()).code, 0);
  // The states alone, without their derivatives; and with a trajectory column.
  const std::vector<std::string> rows = lines(read_text(csv));
  std::string bare, with_id;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    std::stringstream in(rows[i]);
    std::vector<std::string> cells;
    for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
    bare += fmt::format("{}\n", fmt::join(cells.begin(), cells.begin() + 4, ","));
    with_id += (i == 0 ? std::string("trajectory") : std::to_string(i % 3)) + "," + rows[i] + "\n";
  }
  write_text(dir / "bare.csv", bare);
  write_text(dir / "with_id.csv", with_id);
  const auto train = [&](const fs::path& file, std::vector<std::string> extra) {
    std::vector<std::string> args = {"train",    "data",      "--data", file.string(), "--coords",
                                     "x,y",      "--momenta", "px,py",  "--steps",     "2",
                                     "--hidden", "4",         "--out",  out.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  const std::vector<BadScattered> cases = {
      {train(dir / "bare.csv", {}),
       (dir / "bare.csv").string() +
           ": no time column (none is named t, time or times) and no derivative columns: give the "
           "time column by name or index, or for scattered states dx/dt of every state column "
           "(named d<x>/dt, or chosen with --derivatives) (columns: x, y, px, py)\n"},
      {train(dir / "with_id.csv", {}),
       (dir / "with_id.csv").string() +
           ": a trajectory column ('trajectory') but no time column (none is named t, time or "
           "times): give the time column, or drop the trajectory column for scattered states\n"},
      {train(csv, {"--derivatives", "none"}), csv.string() + ": no time column (none is named t, "
                                                             "time or times) and no derivative "
                                                             "columns (--derivatives none): "},
      {train(csv, {"--split", "time"}),
       csv.string() + ": split by time needs trajectories, and the file holds scattered states (no "
                      "time column): leave the split at auto (the last rows are the test set)\n"},
      {train(csv, {"--settings", "{\"rollouts\": 5}"}),
       csv.string() + ": the setting rollouts needs trajectories, and the file holds scattered "
                      "states (no time column): leave it out\n"},
      {train(csv, {"--loss", "rollout"}),
       csv.string() + ": the rollout loss needs trajectories, and the file holds scattered states "
                      "(no time column): use --loss derivative\n"},
      {{"simulate", "--hamiltonian", "p^2/2", "--coords", "q", "--momenta", "p", "--scattered", "5",
        "--trajectories", "2", "--out", (dir / "x.csv").string()},
       "--trajectories excludes --scattered"},
      {{"simulate", "--hamiltonian", "p^2/2", "--coords", "q", "--momenta", "p", "--scattered", "5",
        "--integrator", "rk4", "--out", (dir / "x.csv").string()},
       "--integrator excludes --scattered"},
      {{"simulate", "--hamiltonian", "p^2/2", "--coords", "q", "--momenta", "p", "--out",
        (dir / "x.csv").string()},
       "give --trajectories, --t-end and --points for trajectories, or --scattered N for N states "
       "without time (uniform in --sample's box, with exact dx/dt)\n"},
  };
  for (const BadScattered& bad : cases) {
    const Result r = run_hnn(bad.args, dir.path());
    const std::string what = fmt::format("{}", fmt::join(bad.args, " "));
    expect_one_line_error_starting(r, bad.message, what);
    EXPECT_FALSE(fs::exists(out)) << what;
    EXPECT_FALSE(fs::exists(dir / "x.csv")) << what;
  }
}

}  // namespace
}  // namespace hnn::reliability
