#pragma once
// Numbers in and out of the JSON files of runs: JSON has no NaN (a missing number is null), and
// nlohmann's get<int>() of a float or an out-of-range number is undefined behaviour, so integers
// are read through a check.

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "tasks/error.h"

namespace hnn::tasks {

/// v, or null when v is not finite.
inline nlohmann::json number(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}
/// The inverse of number(): null reads as NaN.
inline double number_or_nan(const nlohmann::json& j) {
  return j.is_null() ? std::numeric_limits<double>::quiet_NaN() : j.get<double>();
}

/// `j` as an integer of type I. Throws Error naming `what` unless it is an integer number in I's
/// range.
template <typename I>
I json_integer(const nlohmann::json& j, const std::string& what) {
  constexpr auto kMin = std::numeric_limits<I>::min();
  constexpr auto kMax = std::numeric_limits<I>::max();
  if (j.is_number_unsigned() && j.get<std::uint64_t>() <= std::uint64_t(kMax)) {
    return I(j.get<std::uint64_t>());
  }
  if (j.is_number_integer() && !j.is_number_unsigned()) {
    const std::int64_t v = j.get<std::int64_t>();
    if (v >= 0 ? std::uint64_t(v) <= std::uint64_t(kMax) : kMin < 0 && v >= std::int64_t(kMin)) {
      return I(v);
    }
  }
  throw Error(fmt::format("{} is {}, not an integer from {} to {}", what, j.dump(), kMin, kMax));
}

/// The JSON document in `path`; throws Error naming the file when it cannot be read or parsed.
nlohmann::json read_json_file(const std::filesystem::path& path);

}  // namespace hnn::tasks
