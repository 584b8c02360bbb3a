#pragma once
// A data file read into one table: named columns of doubles, with where each row came from so
// that every later message can name the file and the line (or row). The readers of CSV, NumPy
// .npy/.npz and the Schmidt & Lipson text format all produce it; measured_trajectories.h turns
// it into trajectories.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace hnn::tasks {

enum class TableFormat { kCsv, kNpy, kNpz, kLipson };

struct Table {
  std::string source;  ///< the file, as given, for messages
  TableFormat format = TableFormat::kCsv;
  std::vector<std::string> names;  ///< one per column, unique
  Eigen::MatrixXd values;          ///< rows x columns, all finite
  std::vector<int> lines;          ///< per row its line in the file (text formats); else empty
  /// Lipson files: the state columns the '%' header names (their default coordinates and
  /// velocities); empty for the other formats.
  std::vector<std::string> header_state;

  Eigen::Index rows() const { return values.rows(); }
  Eigen::Index columns() const { return values.cols(); }
  /// "FILE:LINE" for text formats, "FILE: row R" (0-based, as NumPy counts) for arrays.
  std::string where(Eigen::Index row) const;
  /// The column a choice names: an exact column name first, else a 0-based index written in
  /// digits. Throws tasks::Error naming the file and the known columns when there is none.
  Eigen::Index column(const std::string& name_or_index) const;
  /// Like column(), but a name that is an npz 2-D array's ("q" for q[0], q[1], ...) gives all
  /// of its columns in order.
  std::vector<Eigen::Index> columns_of(const std::string& name_or_index) const;
  /// The index of the column named exactly `name`, or -1.
  Eigen::Index find(const std::string& name) const;
};

/// Reads a data file by its extension: .csv, .npy, .npz, or .txt (Schmidt & Lipson). Throws
/// tasks::Error naming the file on a missing, unreadable or unknown file and on bad contents.
Table read_table(const std::string& path);

/// CSV with a header row naming the columns: comma-separated, LF or CRLF, blank lines skipped,
/// names optionally in double quotes, every cell a finite number.
Table read_csv(const std::string& path);

/// The Schmidt & Lipson text format: columns "trial", "t", the names of the '%' header, then any
/// further columns, named "d<name>" when there are as many as the header names (the files'
/// derivatives, data/lipson/README.md) and by their 0-based index otherwise.
Table read_lipson(const std::string& path);

/// A NumPy .npy file holding a 2-D float64 or float32 array; columns named "0", "1", ...
Table read_npy(const std::string& path);

/// A NumPy .npz archive (savez or savez_compressed) of float64/float32 arrays of one length: a
/// 1-D array "x" is the column "x", a 2-D array "q" of k columns is "q[0]" ... "q[k-1]".
Table read_npz(const std::string& path);

}  // namespace hnn::tasks
