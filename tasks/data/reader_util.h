#pragma once
// Checks the table readers share (table.cpp): a readable file, unique column names, finite
// numbers; and the layout of an .npz of trajectories (npz_trajectories.cpp). Each throws
// tasks::Error whose message starts with where the problem is.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tasks/data/table.h"

namespace hnn::tasks::reader {

/// Throws unless `path` is an existing regular file that opens for reading.
void check_readable(const std::string& path);

/// The whole file as bytes.
std::string read_bytes(const std::string& path);

/// Throws "WHERE: column 'x' appears twice (columns 1 and 3)" on a repeated or empty name.
void check_unique_names(const std::vector<std::string>& names, const std::string& where);

/// A decimal number (strtod syntax: 1, -2.5e3, .5) that is finite; throws "WHERE: what: 'text'
/// is not a number" (or "is not finite", "is out of the range of a double").
double parse_finite(const std::string& text, const std::string& where, const std::string& what);

/// A NumPy shape as "6x3" ("a scalar" for none).
std::string shape_text(const std::vector<std::size_t>& shape);

/// A NumPy array as rows x its last axis: a 1-D array is one column; a 3-D one (n, m, k) has
/// row i * m + j for [i, j, :].
struct NumpyArray {
  std::vector<std::size_t> shape;
  Eigen::MatrixXd columns;
};
using NamedArrays = std::vector<std::pair<std::string, NumpyArray>>;

/// (trajectories, times) when an .npz holds trajectories rather than columns: some array is
/// trajectories x times x components, or its time (t, time or times) is trajectories x times,
/// or its time has T values and another array is N x T (N != T).
std::optional<std::pair<std::size_t, std::size_t>> trajectory_shape(const NamedArrays& arrays);

/// The columns of an .npz of `shape` trajectories, one row per trajectory and time: an
/// N x T x k array gives "x[0]" .. "x[k-1]", an N x T one "x", a T one (the times) and an N
/// one (a value per trajectory) "x" repeated; a column "trajectory" (0 .. N-1) is added unless
/// an array has that name. Throws naming an array of another shape.
void trajectory_columns(const NamedArrays& arrays, std::pair<std::size_t, std::size_t> shape,
                        Table& table);

}  // namespace hnn::tasks::reader
