// The initial states a user gives `hnn rollout` (tasks/data/initial_states.h): read against the
// run's state columns by name or as x_0..x_{d-1}, in any order, and every bad one a message
// naming where.

#include "tasks/data/initial_states.h"

#include <gtest/gtest.h>

#include "data_files_util.h"

namespace hnn::tasks {
namespace {

using testing::error_of;

const std::vector<std::string> kNames = {"q", "p"};

TEST(InitialStates, ValuesAreOneStateEachInTheRunsOrder) {
  const physics::Batch x = states_from_values({"1, -2.5", "3e-1,0"}, kNames);
  ASSERT_EQ(x.rows(), 2);
  EXPECT_EQ(x(0, 0), 1.0);
  EXPECT_EQ(x(0, 1), -2.5);
  EXPECT_EQ(x(1, 0), 0.3);
  EXPECT_EQ(error_of([] { states_from_values({"1,2,3"}, kNames); }),
            "--state '1,2,3': 3 numbers, and a state has 2: q, p");
  EXPECT_EQ(error_of([] { states_from_values({"1,"}, kNames); }),
            "--state '1,': value 2 (p): '' is not a number");
  EXPECT_EQ(error_of([] { states_from_values({"nan,1"}, kNames); }),
            "--state 'nan,1': value 1 (q): 'nan' is not finite");
}

class InitialStatesFile : public testing::DataFilesTest {};

TEST_F(InitialStatesFile, NamesOrNumberedColumnsInAnyOrder) {
  const physics::Batch x = states_from_file(write("s.csv", "p,q\n2,1\n4,3\n"), kNames);
  ASSERT_EQ(x.rows(), 2);
  EXPECT_EQ(x(1, 0), 3.0);
  EXPECT_EQ(x(1, 1), 4.0);
  EXPECT_EQ(states_from_file(write("n.csv", "x_1,x_0\n2,1\n"), kNames)(0, 0), 1.0);
}

TEST_F(InitialStatesFile, AnUnknownMissingOrRepeatedColumnOrABadCellIsNamed) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"q,r\n1,2\n",
       ": header: column 'r' is not a state column; the run's are q, p (or x_0, x_1)"},
      {"q\n1\n", ": header: no column 'p'; a state has q, p (or x_0, x_1)"},
      {"q,x_0,p\n1,1,2\n", ": header: columns 'q' and 'x_0' both name state column 'q'"},
      {"q,p\n1,2\n1,two\n", ":3: column 'p': 'two' is not a number"},
      {"q,p\n1,2,3\n", ":2: 3 cells where the header names 2 columns"}};
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const std::string file = write("bad" + std::to_string(i) + ".csv", cases[i].first);
    EXPECT_EQ(error_of([&] { states_from_file(file, kNames); }), file + cases[i].second);
  }
}

}  // namespace
}  // namespace hnn::tasks
