#pragma once
// An enum's names, declared once as a table of (value, name) pairs and read both ways: the name
// of a value, the value of a name, and the list of names (for --help, checks and messages). The
// enums of nn/ and of tasks/ (which is above nn/) declare their tables with it; so a new value
// needs one line, and its name, its parse and its place in every list cannot drift apart.
//
//   constexpr nn::NameTable<Activation, 2> kNames{{{Activation::kTanh, "tanh"}, ...}};
//   to_string(a)         -> nn::name_of(kNames, a)
//   parse_activation(s)  -> nn::parse_name(kNames, s, "activation")
//   activation_names()   -> nn::names_of(kNames)

#include <fmt/format.h>

#include <array>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hnn::nn {

template <typename E, std::size_t N>
using NameTable = std::array<std::pair<E, std::string_view>, N>;

/// The name of value, or "unknown" for a value the table lacks.
template <typename E, std::size_t N>
constexpr std::string_view name_of(const NameTable<E, N>& table, E value) {
  for (const auto& [v, name] : table) {
    if (v == value) return name;
  }
  return "unknown";
}

/// The value named text, or nullopt (for a caller that words its own error).
template <typename E, std::size_t N>
constexpr std::optional<E> find_name(const NameTable<E, N>& table, std::string_view text) {
  for (const auto& [v, name] : table) {
    if (name == text) return v;
  }
  return std::nullopt;
}

/// The names in the table's order.
template <typename E, std::size_t N>
std::vector<std::string> names_of(const NameTable<E, N>& table) {
  std::vector<std::string> names;
  for (const auto& [v, name] : table) names.emplace_back(name);
  return names;
}

/// The names in the table's order, joined by ", " and the last two by last: with last = " or ",
/// "a, b or c".
template <typename E, std::size_t N>
std::string join_names(const NameTable<E, N>& table, std::string_view last = ", ") {
  std::string joined;
  for (std::size_t i = 0; i < N; ++i) {
    if (i > 0) joined += i + 1 == N ? last : std::string_view(", ");
    joined += table[i].second;
  }
  return joined;
}

/// The value named text; throws std::invalid_argument
/// "unknown WHAT 'TEXT' (expected one of: a, b, c)" on any other text.
template <typename E, std::size_t N>
E parse_name(const NameTable<E, N>& table, std::string_view text, std::string_view what) {
  if (const std::optional<E> value = find_name(table, text)) return *value;
  throw std::invalid_argument(
      fmt::format("unknown {} '{}' (expected one of: {})", what, text, join_names(table)));
}

}  // namespace hnn::nn
