// `hnn simulate`: a short run read back (header, counts, dx/dt equal to the exact field, the
// noise on the states only, the same file for the same seed), and every bad option: one line
// "hnn: error: ...", exit 1, no file (docs/inputs.md, "hnn simulate").

#include <gtest/gtest.h>

#include "physics/expression_system.h"
#include "reliability_util.h"

namespace hnn::reliability {
namespace {

const char* const kPendulum = "p^2/2 + 9.81*(1 - cos(q))";

std::vector<std::string> simulate_args(const std::string& hamiltonian, const fs::path& out) {
  return {"simulate", "--hamiltonian",  hamiltonian, "--coords", "q",         "--momenta",
          "p",        "--trajectories", "4",         "--t-end",  "2",         "--points",
          "6",        "--seed",         "3",         "--out",    out.string()};
}

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
};

Csv read_csv(const fs::path& path) {
  Csv csv;
  for (const std::string& line : lines(read_text(path))) {
    std::vector<std::string> cells;
    std::stringstream in(line);
    for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
    if (csv.header.empty()) {
      csv.header = cells;
      continue;
    }
    std::vector<double> row;
    for (const std::string& cell : cells) row.push_back(std::stod(cell));
    csv.rows.push_back(row);
  }
  return csv;
}

// Columns [first, first + count) of every row.
physics::Batch columns(const Csv& csv, int first, int count) {
  physics::Batch x(Eigen::Index(csv.rows.size()), count);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (int j = 0; j < count; ++j) x(i, j) = csv.rows[std::size_t(i)][std::size_t(first + j)];
  }
  return x;
}

TEST(Simulate, WritesTrajectoriesWithTheExactDerivatives) {
  const TempDir dir;
  const Result r = run_hnn(simulate_args(kPendulum, dir / "a.csv"), dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  const Csv csv = read_csv(dir / "a.csv");
  EXPECT_EQ(csv.header, (std::vector<std::string>{"trajectory", "t", "q", "p", "dq/dt", "dp/dt"}));
  ASSERT_EQ(csv.rows.size(), 24u);
  EXPECT_EQ(csv.rows[5][0], 0.0);  // trajectory-major: 6 times of trajectory 0 first
  EXPECT_EQ(csv.rows[6][0], 1.0);
  EXPECT_EQ(csv.rows[5][1], 2.0);
  EXPECT_DOUBLE_EQ(csv.rows[7][1], 0.4);
  const physics::ExpressionSystem system(kPendulum, {"q"}, {"p"});
  physics::Batch field;
  system.vector_field(columns(csv, 2, 2), field);
  EXPECT_LT((columns(csv, 4, 2) - field).cwiseAbs().maxCoeff(), 1e-14);
  const Eigen::VectorXd h = system.hamiltonian_batch(columns(csv, 2, 2));
  EXPECT_LT((h.array() - h(0)).head(6).abs().maxCoeff(), 1e-8);  // dopri5 at rtol 1e-10

  // The same seed gives the same file; noise moves the states, not the derivatives.
  ASSERT_EQ(run_hnn(simulate_args(kPendulum, dir / "b.csv"), dir.path()).code, 0);
  EXPECT_EQ(read_text(dir / "a.csv"), read_text(dir / "b.csv"));
  std::vector<std::string> noisy = simulate_args(kPendulum, dir / "noisy.csv");
  noisy.insert(noisy.end(), {"--noise", "0.1"});
  ASSERT_EQ(run_hnn(noisy, dir.path()).code, 0);
  const Csv n = read_csv(dir / "noisy.csv");
  EXPECT_EQ(columns(n, 4, 2), columns(csv, 4, 2));
  const double shift = (columns(n, 2, 2) - columns(csv, 2, 2)).cwiseAbs().maxCoeff();
  EXPECT_GT(shift, 0.01);
  EXPECT_LT(shift, 1.0);
}

TEST(Simulate, TwoDegreesOfFreedomFromAnEnergyBand) {
  const TempDir dir;
  const Result r = run_hnn({"simulate",
                            "--hamiltonian",
                            "(px^2+py^2)/2 + (x^2+y^2)/2 + x^2*y - y^3/3",
                            "--coords",
                            "x,y",
                            "--momenta",
                            "px",
                            "--momenta",
                            "py",
                            "--trajectories",
                            "3",
                            "--t-end",
                            "1",
                            "--points",
                            "3",
                            "--energy",
                            "0.05:0.1",
                            "--sample",
                            "x=-0.4:0.4,y=-0.4:0.4,px=-0.4:0.4,py=-0.4:0.4",
                            "--integrator",
                            "yoshida4",
                            "--dt",
                            "0.001",
                            "--out",
                            (dir / "hh.csv").string()},
                           dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  const Csv csv = read_csv(dir / "hh.csv");
  EXPECT_EQ(csv.header, (std::vector<std::string>{"trajectory", "t", "x", "y", "px", "py", "dx/dt",
                                                  "dy/dt", "dpx/dt", "dpy/dt"}));
  ASSERT_EQ(csv.rows.size(), 9u);
  const physics::ExpressionSystem hh("(px^2+py^2)/2 + (x^2+y^2)/2 + x^2*y - y^3/3", {"x", "y"},
                                     {"px", "py"});
  const Eigen::VectorXd h = hh.hamiltonian_batch(columns(csv, 2, 4));
  EXPECT_GE(h.minCoeff(), 0.05 - 1e-6);
  EXPECT_LE(h.maxCoeff(), 0.1 + 1e-6);
}

struct BadSimulate {
  std::vector<std::string> replace;  // option, value pairs replacing (or adding to) the defaults
  std::string message;               // the start of the line after "hnn: error: "
};

std::vector<std::string> with(std::vector<std::string> args, const std::vector<std::string>& r) {
  for (std::size_t i = 0; i + 1 < r.size(); i += 2) {
    const auto at = std::find(args.begin(), args.end(), r[i]);
    if (at == args.end()) {
      args.insert(args.end(), {r[i], r[i + 1]});
    } else {
      *(at + 1) = r[i + 1];
    }
  }
  return args;
}

TEST(Simulate, BadOptionsGetOneLineAndNoFile) {
  const TempDir dir;
  const std::string too_few = "hamiltonian: 2 coordinates (x, y) and 1 momenta (p): give one ";
  const std::vector<BadSimulate> cases = {
      {{"--hamiltonian", "p^2/2 +"},
       "hamiltonian 'p^2/2 +' does not parse: unexpected token, got: EOF\n"},
      {{"--hamiltonian", "p^2/2 + r*q"},
       "hamiltonian 'p^2/2 + r*q': unknown name 'r' (coordinates: q; momenta: p)\n"},
      {{"--coords", "x,y"}, too_few},
      {{"--momenta", "q"}, "hamiltonian: the name 'q' is given twice (coordinates q; momenta q)\n"},
      {{"--coords", "cos"}, "hamiltonian: coordinate name 'cos' is a function or constant"},
      {{"--hamiltonian", "sqrt(q) + p^2/2", "--sample", "q=-2:-1"},
       "H = sqrt(q) + p^2/2: -dH/dq is NaN at state 0 (q = -"},
      {{"--hamiltonian", "(q^2 + 1)*(p^2 + 1)/2", "--integrator", "leapfrog"},
       "leapfrog needs a separable Hamiltonian H = T(p) + V(q); H = (q^2 + 1)*(p^2 + 1)/2 is "
       "not: use midpoint (symplectic), rk4 or dopri5\n"},
      {{"--integrator", "rk5"}, "unknown integrator 'rk5'; known: euler, rk4, dopri5, "},
      {{"--sample", "q=1"}, "--sample q: '1' is not LO:HI with two numbers (e.g. -1:1)\n"},
      {{"--sample", "q"}, "--sample: 'q' is not NAME=LO:HI (e.g. q=-1:1,p=-1:1)\n"},
      {{"--sample", "q=0:1,q=1:2"}, "--sample: 'q' has two ranges\n"},
      {{"--sample", "r=0:1"},
       "sampling range for 'r', which is not a coordinate or momentum (q, p)\n"},
      {{"--sample", "q=1:0"}, "sampling range of 'q' is 1:0; it needs finite lo < hi\n"},
      {{"--energy", "1"}, "--energy: '1' is not LO:HI with two numbers (e.g. -1:1)\n"},
      {{"--energy", "2:1"}, "energy band 2:1 needs finite LO <= HI\n"},
      {{"--energy", "100:200"}, "H = p^2/2 + 9.81*(1 - cos(q)): only 0 of 4 states with H in "},
      {{"--noise", "-1"}, "--noise: expected a finite number >= 0, got '-1' (see --help)\n"},
      {{"--t-end", "0"}, "--t-end: expected a finite number > 0, got '0' (see --help)\n"},
      {{"--points", "1"}, "--points: expected an integer from 2 to 10000000, got '1'"},
      {{"--trajectories", "0"}, "--trajectories: expected an integer from 1 to 10000000, got '0'"},
      {{"--dt", "nan"}, "--dt: expected a finite number > 0, got 'nan' (see --help)\n"},
      {{"--trajectories", "10000000", "--points", "100"},
       "--trajectories 10000000 x --points 100 is more than 1e+08 rows\n"},
      {{"--hamiltonian", "p^2/2 + q**4"},
       "hamiltonian 'p^2/2 + q**4' does not parse: unexpected token, got: \"*\" (write powers with "
       "^: q^4, not q**4)\n"},
      {{"--out", (dir / "missing" / "x.csv").string()},
       "cannot write '" + (dir / "missing" / "x.csv").string() + "' (its folder '" +
           (dir / "missing").string() + "' does not exist): No such file or directory\n"},
  };
  const fs::path out = dir / "out.csv";
  for (const BadSimulate& bad : cases) {
    const std::vector<std::string> args = with(simulate_args(kPendulum, out), bad.replace);
    const Result r = run_hnn(args, dir.path());
    const std::string what = bad.replace[0] + " " + bad.replace[1];
    expect_one_line_error_starting(r, bad.message, what);
    EXPECT_FALSE(fs::exists(out)) << what;
  }
  const Result missing = run_hnn({"simulate", "--hamiltonian", "q^2"}, dir.path());
  EXPECT_EQ(missing.err, "hnn: error: --coords is required (see --help)\n");
}

}  // namespace
}  // namespace hnn::reliability
