// Reproducibility: two runs with the same seed write bit-identical files (metrics.json except
// its *_seconds timings); another seed gives other data, weights and results.

#include <gtest/gtest.h>

#include "reliability_util.h"

namespace hnn::reliability {
namespace {

Result train(const TempDir& dir, const std::string& name, const std::string& seed,
             const std::vector<std::string>& extra) {
  std::vector<std::string> args = {"train",
                                   "spring",
                                   "--hidden",
                                   "8",
                                   "--steps",
                                   "30",
                                   "--batch",
                                   "25",
                                   "--seed",
                                   seed,
                                   "--quiet",
                                   "--out",
                                   (dir / name).string()};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_hnn(args, dir.path());
}

void expect_same_seed_same_files(const std::vector<std::string>& extra) {
  const TempDir dir;
  for (const char* name : {"a", "b"}) ASSERT_EQ(train(dir, name, "11", extra).code, 0);
  ASSERT_EQ(train(dir, "c", "12", extra).code, 0);
  for (const char* file : {"params.bin", "loss_curve.csv", "rollout.csv"}) {
    EXPECT_EQ(read_text(dir / "a" / file), read_text(dir / "b" / file)) << file;
    EXPECT_NE(read_text(dir / "a" / file), read_text(dir / "c" / file)) << file;
  }
  const nlohmann::json a = read_json(dir / "a" / "metrics.json");
  const nlohmann::json b = read_json(dir / "b" / "metrics.json");
  const nlohmann::json c = read_json(dir / "c" / "metrics.json");
  EXPECT_EQ(without_timings(a), without_timings(b));
  // Only the timings are left out, and every other key is there.
  EXPECT_EQ(a.size(), without_timings(a).size() + 4);
  for (const char* key : {"train_loss", "test_loss", "energy_mse", "final_batch_loss"}) {
    EXPECT_NE(a[key], c[key]) << key;
  }
}

TEST(Determinism, SameSeedSameFilesOtherSeedOtherResults) { expect_same_seed_same_files({}); }

TEST(Determinism, HoldsForFloatAndTheBaselineToo) {
  expect_same_seed_same_files({"--dtype", "float", "--model", "baseline"});
}

}  // namespace
}  // namespace hnn::reliability
