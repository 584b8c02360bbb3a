// Output paths that cannot be: a folder under a regular file (`--out afile/sub`), or a file in a
// folder that does not exist. One line naming the path and the file or folder at fault, never
// a raw std::filesystem message or the writer's temporary file (docs/inputs.md).

#include <gtest/gtest.h>

#include "reliability_util.h"

namespace hnn::reliability {
namespace {

TEST(OutPaths, UnderARegularFileOrInAMissingFolderGetOneLineNamingIt) {
  const TempDir dir;
  const std::string file = (dir / "afile").string();
  write_text(file, "not a folder\n");
  const std::vector<std::string> simulate = {"simulate",
                                             "--hamiltonian",
                                             "p^2/2 + q^2/2",
                                             "--coords",
                                             "q",
                                             "--momenta",
                                             "p",
                                             "--trajectories",
                                             "2",
                                             "--t-end",
                                             "1",
                                             "--points",
                                             "3",
                                             "--out"};
  const auto with_out = [](std::vector<std::string> args, const std::string& out) {
    args.push_back(out);
    return args;
  };
  const struct Case {
    std::vector<std::string> args;
    std::string line;
  } cases[] = {
      {{"train", "spring", "--steps", "1", "--hidden", "4", "--quiet", "--out", file + "/sub"},
       "hnn: error: '" + file + "/sub': '" + file +
           "' is a file, not a folder (cannot create directories)\n"},
      {with_out(simulate, file + "/x.csv"), "hnn: error: cannot write '" + file + "/x.csv' ('" +
                                                file +
                                                "' is a file, not a folder): Not a directory\n"},
      {with_out(simulate, (dir / "missing" / "x.csv").string()),
       "hnn: error: cannot write '" + (dir / "missing" / "x.csv").string() + "' (its folder '" +
           (dir / "missing").string() + "' does not exist): No such file or directory\n"},
  };
  for (const Case& c : cases) {
    const Result r = run_hnn(c.args, dir.path());
    EXPECT_EQ(r.code, 1) << c.line;
    EXPECT_EQ(r.err, c.line);
  }
  EXPECT_EQ(read_text(file), "not a folder\n");
}

}  // namespace
}  // namespace hnn::reliability
