#pragma once
// Checks the table readers share (table.cpp): a readable file, unique column names, finite
// numbers. Each throws tasks::Error whose message starts with where the problem is.

#include <string>
#include <vector>

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

}  // namespace hnn::tasks::reader
