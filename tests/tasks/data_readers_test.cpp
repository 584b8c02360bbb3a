// The table readers of tasks/data/table.h: CSV, the Schmidt & Lipson text format (the shipped
// files and every variant), NumPy .npy and .npz (fixtures written by numpy itself:
// tests/tasks/fixtures/make_numpy_fixtures.py), and each bad input with its whole message.

#include <gtest/gtest.h>

#include "tasks/data/table.h"
#include "tests/tasks/data_files_util.h"

namespace hnn::tasks {
namespace {

using testing::crlf;
using testing::error_of;
using testing::fixture;
using Names = std::vector<std::string>;

class CsvReader : public testing::DataFilesTest {};
class LipsonReader : public testing::DataFilesTest {};
class NumpyReader : public testing::DataFilesTest {};
class TableFiles : public testing::DataFilesTest {};

TEST_F(CsvReader, ReadsNamesValuesAndLinesWithLfOrCrlfAndBlankLines) {
  const std::string text = "t,q,p\n0,1,2\n\n  \n0.5, -3e2 ,+4\n";
  for (const std::string& bytes : {text, crlf(text)}) {
    const Table table = read_csv(write("a.csv", bytes));
    EXPECT_EQ(table.format, TableFormat::kCsv);
    EXPECT_EQ(table.names, (Names{"t", "q", "p"}));
    ASSERT_EQ(table.rows(), 2);
    EXPECT_EQ(table.values.row(1), Eigen::RowVector3d(0.5, -300, 4));
    EXPECT_EQ(table.lines, (std::vector<int>{2, 5}));
    EXPECT_EQ(table.where(1), table.source + ":5");
  }
}

TEST_F(CsvReader, QuotedNamesAndCellsAndAByteOrderMark) {
  const Table table =
      read_csv(write("q.csv", "\xEF\xBB\xBF\"t\",\"x, y\",\"say \"\"p\"\"\"\n1,\"2\",3\n"));
  EXPECT_EQ(table.names, (Names{"t", "x, y", "say \"p\""}));
  EXPECT_EQ(table.values.row(0), Eigen::RowVector3d(1, 2, 3));
  EXPECT_EQ(table.column("x, y"), 1);
  EXPECT_EQ(table.column("2"), 2);  // an index when no column has that name
}

TEST_F(CsvReader, EveryBadInputIsOneLineNamingFileLineAndWhat) {
  const struct Case {
    std::string name, text, message;
  } cases[] = {
      {"empty", "", ": empty file (a header row naming the columns is needed)"},
      {"header_only", "\nt,q,p\n", ":2: no data rows after the header"},
      {"duplicate", "t,q,q\n1,2,3\n", ":1: column 'q' appears twice (columns 1 and 2)"},
      {"unnamed", "t,,p\n1,2,3\n", ":1: column 1 has no name"},
      {"ragged", "t,q,p\n1,2,3\n1,2\n", ":3: 2 cells where the header names 3 columns"},
      {"text", "t,q,p\n1,abc,3\n", ":2: column 'q': 'abc' is not a number"},
      {"empty_cell", "t,q,p\n1,,3\n", ":2: column 'q': '' is not a number"},
      {"nan", "t,q,p\n1,2,3\n2,nan,3\n", ":3: column 'q': 'nan' is not finite"},
      {"inf", "t,q,p\n1,2,-inf\n", ":2: column 'p': '-inf' is not finite"},
      {"huge", "t,q,p\n1,1e999,3\n", ":2: column 'q': '1e999' is out of the range of a double"},
      {"quote", "t,q,p\n1,\"2,3\n", ":2: a double quote is not closed"},
  };
  for (const Case& c : cases) {
    const std::string path = write(c.name + ".csv", c.text);
    EXPECT_EQ(error_of([&] { read_table(path); }), path + c.message) << c.name;
  }
}

TEST_F(LipsonReader, ReadsEveryShippedFile) {
  const struct Shipped {
    std::string file;
    Eigen::Index rows;
    Names names;
  } files[] = {
      {"real_pend_h_1.txt", 556, {"trial", "t", "o", "v"}},
      {"pendulum_h_1.txt", 493, {"trial", "t", "o", "v", "do", "dv"}},
      {"real_double_pend_h_1.txt",
       1520,
       {"trial", "t", "o1", "o2", "w1", "w2", "do1", "do2", "dw1", "dw2"}},
      {"double_pend_h_1.txt",
       2516,
       {"trial", "t", "o1", "o2", "w1", "w2", "do1", "do2", "dw1", "dw2"}},
  };
  for (const Shipped& f : files) {
    const Table table = read_table(std::string(HNN_SOURCE_DIR) + "/data/lipson/" + f.file);
    EXPECT_EQ(table.format, TableFormat::kLipson);
    EXPECT_EQ(table.rows(), f.rows) << f.file;
    EXPECT_EQ(table.names, f.names) << f.file;
    EXPECT_EQ(table.header_state,
              Names(f.names.begin() + 2, f.names.begin() + 2 + (f.names.size() > 6 ? 4 : 2)))
        << f.file;
    EXPECT_EQ(table.lines.front(), 2) << f.file;  // line 1 is the '%' header
  }
  const Table real = read_table(std::string(HNN_SOURCE_DIR) + "/data/lipson/real_pend_h_1.txt");
  EXPECT_EQ(real.values.row(0), Eigen::RowVector4d(0, 5.0, 1.1383885512243586, 0.9197795905867725));
}

TEST_F(LipsonReader, HeaderVariantsExtraColumnsCrlfAndBlankLines) {
  const std::string spaced = "% x v\n0 0.0 1 2 7\n\n0 0.1 3 4 8\n";
  for (const std::string& bytes :
       {spaced, crlf(spaced), std::string("%x v\n0 0.0 1 2 7\n0 0.1 3 4 8\n")}) {
    const Table table = read_table(write("v.txt", bytes));
    EXPECT_EQ(table.names, (Names{"trial", "t", "x", "v", "4"}));  // the extra one by its index
    EXPECT_EQ(table.header_state, (Names{"x", "v"}));
    EXPECT_EQ(table.values.row(1), (Eigen::RowVectorXd(5) << 0, 0.1, 3, 4, 8).finished());
  }
  const Table two = read_table(write("two.txt", "% x1 x2 v1 v2\n1 0 1 2 3 4\n1 1 5 6 7 8\n"));
  EXPECT_EQ(two.names, (Names{"trial", "t", "x1", "x2", "v1", "v2"}));
}

TEST_F(LipsonReader, BadInputsNameTheFileAndLine) {
  const struct Case {
    std::string name, text, message;
  } cases[] = {
      {"text", "% x v\n0 0 1 2\n0 1 abc 2\n", ":3: column 3: 'abc' is not a number"},
      {"nan", "% x v\n0 0 1 nan\n", ":2: column 4: 'nan' is not finite"},
      {"no_header", "0 0 1 2\n", ":1: expected a header line starting with '%' naming the columns"},
      {"names_t", "% t v\n0 0 1 2\n",
       ": the '%' header: column 't' appears twice (columns 1 and 2)"},
  };
  for (const Case& c : cases) {
    const std::string path = write(c.name + ".txt", c.text);
    EXPECT_EQ(error_of([&] { read_table(path); }), path + c.message) << c.name;
  }
}

TEST_F(NumpyReader, NpyColumnsAreNamedByIndexInEitherOrderAndPrecision) {
  const Table f64 = read_table(fixture("quadratic.npy"));
  EXPECT_EQ(f64.format, TableFormat::kNpy);
  EXPECT_EQ(f64.names, (Names{"0", "1", "2"}));
  ASSERT_EQ(f64.rows(), 6);
  EXPECT_EQ(f64.values.row(5), Eigen::RowVector3d(1.0, 6.0, -1.0));
  EXPECT_EQ(f64.values(1, 0), 0.2);
  EXPECT_EQ(f64.where(3), fixture("quadratic.npy") + ": row 3");
  const Table f32 = read_table(fixture("quadratic_f32_fortran.npy"));
  EXPECT_EQ(f32.names, f64.names);
  EXPECT_TRUE(f32.values.isApprox(f64.values, 1e-7));
  EXPECT_EQ(f32.values(1, 0), double(0.2f));
}

TEST_F(NumpyReader, NpzArraysAreColumnsAndTwoDimensionalOnesSeveral) {
  const Table named = read_table(fixture("two_trajectories.npz"));  // savez_compressed
  EXPECT_EQ(named.format, TableFormat::kNpz);
  EXPECT_EQ(named.names, (Names{"time", "trajectory", "q", "p"}));
  ASSERT_EQ(named.rows(), 12);
  EXPECT_EQ(named.values.row(11), Eigen::RowVector4d(1.0, 1.0, 12.0, -2.0));

  const Table dof = read_table(fixture("two_dof.npz"));  // savez
  EXPECT_EQ(dof.names, (Names{"t", "q[0]", "q[1]", "p[0]", "p[1]"}));
  EXPECT_EQ(dof.columns_of("q"), (std::vector<Eigen::Index>{1, 2}));
  EXPECT_EQ(dof.columns_of("p[1]"), (std::vector<Eigen::Index>{4}));
  EXPECT_EQ(dof.values.row(5), (Eigen::RowVectorXd(5) << 1, 6, -6, -1, -3).finished());
}

TEST_F(NumpyReader, EveryBadArrayIsOneLineNamingFileArrayAndWhat) {
  const auto bad = [](const std::string& name) { return fixture("bad/" + name); };
  const struct Case {
    std::string path, message;
  } cases[] = {
      {bad("int64.npy"), ": holds '<i8' values; only float64 ('<f8') and float32 ('<f4') are read"},
      {bad("three_d.npy"),
       ": an array of shape 2x3x4; a 2-D array (rows x columns) is needed (trajectories x times "
       "x components need their times: save them in an .npz, numpy.savez(FILE, x=x, t=t))"},
      {bad("one_d.npy"), ": an array of shape 6; a 2-D array (rows x columns) is needed"},
      {bad("nan.npy"), ", row 1, column 1: nan is not finite"},
      {cut_copy("quadratic.npy", 200),
       ": truncated: shape 6x3 of '<f8' needs 144 bytes of data, but 72 follow the header"},
      {cut_copy("quadratic.npy", 60),
       ": truncated: the .npy header claims 118 bytes but the file has 60"},
      {write("text.npy", "t,q\n1,2\n"),
       ": not a NumPy .npy array (it does not start with \\x93NUMPY)"},
      {bad("lengths.npz"),
       ": array 'p' has 5 rows but array 't' has 6 (the arrays are the columns of one table and "
       "need one length)"},
      {bad("inf.npz"), ": array 'q', row 3: inf is not finite"},
      {bad("empty.npz"), ": the archive holds no arrays"},
      {bad("text_member.npz"),
       ": member 'notes.txt' is not a .npy array (an .npz holds name.npy members)"},
      {write("text.npz", "t,q\n1,2\n"),
       ": not a readable .npz archive (libzip: Not a zip archive)"},
      {cut_copy("two_dof.npz", 500), ": not a readable .npz archive (libzip: Not a zip archive)"},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(error_of([&] { read_table(c.path); }), c.path + c.message);
  }
}

TEST_F(TableFiles, MissingUnreadableAndUnknownFilesAreNamed) {
  const std::string missing = (dir_ / "nope.csv").string();
  EXPECT_EQ(error_of([&] { read_table(missing); }), missing + ": no such file");
  const std::string folder = (dir_ / "folder.npz").string();
  std::filesystem::create_directories(folder);
  EXPECT_EQ(error_of([&] { read_table(folder); }), folder + ": is a directory, not a data file");
  const std::string xlsx = write("book.xlsx", "PK");
  EXPECT_EQ(error_of([&] { read_table(xlsx); }),
            xlsx +
                ": unknown file type '.xlsx' (known: .csv with a header row, .npy, .npz, and "
                ".txt in the Schmidt & Lipson format)");
  const std::string upper = write("UP.CSV", "t,q\n0,1\n");
  EXPECT_EQ(read_table(upper).names, (Names{"t", "q"}));
}

TEST_F(TableFiles, ColumnChoicesByNameOrIndexAndTheirErrors) {
  const std::string path = write("c.csv", "t,q,p\n0,1,2\n");
  const Table table = read_table(path);
  EXPECT_EQ(table.column("p"), 2);
  EXPECT_EQ(table.column("0"), 0);
  EXPECT_EQ(error_of([&] { table.column("x"); }), path + ": no column 'x' (columns: t, q, p)");
  EXPECT_EQ(error_of([&] { table.column("3"); }),
            path + ": no column 3 (the file has 3 columns, numbered from 0: t, q, p)");
}

}  // namespace
}  // namespace hnn::tasks
