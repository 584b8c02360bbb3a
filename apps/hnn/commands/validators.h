#pragma once
// Option checks of the hnn program whose messages say what is expected (CLI11's own number
// checks print ranges like "0.000000 to 1.797693e308"). Each returns "" when the value is good.

#include <CLI/CLI.hpp>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

namespace hnn::app {

namespace detail {
// The whole of `text` as a number of type N, or false.
template <typename N>
bool parse_whole(const std::string& text, N& value) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  return ec == std::errc() && ptr == end;
}
}  // namespace detail

/// An integer in [min, max].
inline CLI::Validator integer_in(long long min, long long max) {
  return CLI::Validator(
      [min, max](std::string& text) -> std::string {
        long long value = 0;
        if (detail::parse_whole(text, value) && value >= min && value <= max) return "";
        if (max == std::numeric_limits<int>::max()) {
          return "expected an integer >= " + std::to_string(min) + ", got '" + text + "'";
        }
        return "expected an integer from " + std::to_string(min) + " to " + std::to_string(max) +
               ", got '" + text + "'";
      },
      "INT");
}

/// An integer >= 1 that fits an int.
inline CLI::Validator positive_integer() { return integer_in(1, std::numeric_limits<int>::max()); }

/// A seed: an integer from 0 to 2^64 - 1.
inline CLI::Validator seed_value() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::uint64_t value = 0;
        return detail::parse_whole(text, value)
                   ? ""
                   : "expected an integer from 0 to 18446744073709551615, got '" + text + "'";
      },
      "UINT64");
}

/// A finite number > 0.
inline CLI::Validator positive_real() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double value = 0;
        if (detail::parse_whole(text, value) && std::isfinite(value) && value > 0) return "";
        return "expected a finite number > 0, got '" + text + "'";
      },
      "POSITIVE");
}

/// "auto", or a number that `accepts` takes, described as `what` in the message.
inline CLI::Validator auto_or(bool (*accepts)(double), const std::string& what) {
  return CLI::Validator(
      [accepts, what](std::string& text) -> std::string {
        double value = 0;
        if (text == "auto" || (detail::parse_whole(text, value) && accepts(value))) return "";
        return "expected auto or " + what + ", got '" + text + "'";
      },
      "AUTO|X");
}

/// "auto", or a number in (0, 1) (--rcond).
inline CLI::Validator auto_or_fraction() {
  return auto_or([](double v) { return v > 0 && v < 1; }, "a number in (0, 1)");
}

/// "auto", or a finite number > 0 (--swim-scale).
inline CLI::Validator auto_or_positive() {
  return auto_or([](double v) { return std::isfinite(v) && v > 0; }, "a finite number > 0");
}

}  // namespace hnn::app
