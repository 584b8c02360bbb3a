// The spec's keys, `hnn train`'s options as its table declares them
// (tasks/options/train_options.h): each value checked as JSON by its kind, written as `hnn train`
// arguments and in run folder names.

#include "apps/hnn/sweep/keys.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "tasks/experiments/registry.h"

namespace hnn::app::sweep {

namespace fs = std::filesystem;
using nlohmann::json;
using nlohmann::ordered_json;
using tasks::TrainOption;
using tasks::ValueKind;

namespace {

std::string one_of(const ordered_json& v, const std::vector<std::string>& names,
                   std::string_view what) {
  if (v.is_string() && std::find(names.begin(), names.end(), v.get<std::string>()) != names.end())
    return v.get<std::string>();
  if (v.is_string())
    throw std::invalid_argument(fmt::format("unknown {} '{}' (known: {})", what,
                                            v.get<std::string>(), fmt::join(names, ", ")));
  throw std::invalid_argument(
      fmt::format("expected a {} ({}), got {}", what, fmt::join(names, ", "), v.dump()));
}

long long json_integer_in(const ordered_json& v, long long min, long long max) {
  if (v.is_number_integer()) {
    const bool fits =
        v.is_number_unsigned()
            ? v.get<unsigned long long>() >= static_cast<unsigned long long>(std::max(min, 0LL)) &&
                  v.get<unsigned long long>() <= static_cast<unsigned long long>(max)
            : v.get<long long>() >= min && v.get<long long>() <= max;
    if (fits) return v.get<long long>();
  }
  if (max == std::numeric_limits<int>::max())
    throw std::invalid_argument(fmt::format("expected an integer >= {}, got {}", min, v.dump()));
  throw std::invalid_argument(
      fmt::format("expected an integer from {} to {}, got {}", min, max, v.dump()));
}

std::vector<std::string> columns(const ordered_json& v) {
  std::vector<std::string> names;
  if (v.is_string()) {
    std::stringstream in(v.get<std::string>());
    for (std::string name; std::getline(in, name, ',');) names.push_back(name);
  } else if (v.is_array()) {
    for (const ordered_json& name : v) {
      if (!name.is_string()) names.clear();
      if (!name.is_string()) break;
      names.push_back(name.get<std::string>());
    }
  }
  if (names.empty() || std::count(names.begin(), names.end(), "") > 0)
    throw std::invalid_argument(
        fmt::format("expected column names, as \"q1,q2\" or [\"q1\", \"q2\"], got {}", v.dump()));
  return names;
}

std::string number_text(const ordered_json& v) {
  return v.is_number_float() ? fmt::format("{}", v.get<double>()) : v.dump();
}

// Characters safe in a folder name (and unquoted in a shell word); the rest become '-'.
std::string folder_safe(const std::string& text) {
  std::string s;
  for (char c : text) {
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) ||
                    std::string_view("._+=-").find(c) != std::string_view::npos;
    if (ok)
      s += c;
    else if (!s.empty() && s.back() != '-')
      s += '-';
  }
  while (!s.empty() && s.back() == '-') s.pop_back();
  return s.empty() ? "-" : s;
}

// A number kind: which numbers it takes, and how its messages say so.
struct NumberRange {
  bool (*accepts)(double);
  const char* what;
};
constexpr NumberRange kPositiveRange{[](double x) { return std::isfinite(x) && x > 0; },
                                     "a finite number > 0"};
constexpr NumberRange kFractionRange{[](double x) { return x > 0 && x < 1; }, "a number in (0, 1)"};

// v when it is a number in `range` (or "auto", where allowed); else what was expected.
ordered_json checked_number(const ordered_json& v, bool allow_auto, NumberRange range) {
  if ((allow_auto && v == "auto") || (v.is_number() && range.accepts(v.get<double>()))) return v;
  throw std::invalid_argument(
      fmt::format("expected {}{}, got {}", allow_auto ? "\"auto\" or " : "", range.what, v.dump()));
}

}  // namespace

// The value in its canonical form (hidden as a list, a file as an absolute path, ...), or
// std::invalid_argument saying what was expected.
ordered_json checked_value(const TrainOption& key, const ordered_json& v) {
  switch (key.kind) {
    case ValueKind::kTask:
      return one_of(v, tasks::task_names(), "task");
    case ValueKind::kChoice:
      return one_of(v, key.choices(), key.noun);
    case ValueKind::kSeed:
      if (v.is_number_unsigned()) return v;
      throw std::invalid_argument(
          fmt::format("expected an integer from 0 to 18446744073709551615, got {}", v.dump()));
    case ValueKind::kInt:
      return json_integer_in(v, key.min, key.max);
    case ValueKind::kHidden: {
      ordered_json widths = ordered_json::array();
      for (const ordered_json& w : v.is_array() ? v : ordered_json::array({v})) {
        try {
          widths.push_back(json_integer_in(w, 1, tasks::kMaxWidth));
        } catch (const std::invalid_argument&) {
          throw std::invalid_argument(
              fmt::format("expected hidden widths of 1..{}, as [200, 200] or 64, got {}",
                          tasks::kMaxWidth, v.dump()));
        }
      }
      if (widths.empty()) throw std::invalid_argument("expected at least one hidden width, got []");
      return widths;
    }
    case ValueKind::kPositiveReal:
      return checked_number(v, false, kPositiveRange);
    case ValueKind::kFraction:
      return checked_number(v, false, kFractionRange);
    case ValueKind::kAutoOrFraction:
      return checked_number(v, true, kFractionRange);
    case ValueKind::kAutoOrPositive:
      return checked_number(v, true, kPositiveRange);
    case ValueKind::kFile:
      if (v.is_string() && !v.get<std::string>().empty())
        return fs::absolute(v.get<std::string>()).lexically_normal().string();
      throw std::invalid_argument(fmt::format("expected a file name, got {}", v.dump()));
    case ValueKind::kJsonObject:
      if (v.is_object()) return v;
      throw std::invalid_argument(
          fmt::format("expected the task's settings as an object, like {{\"trials\": 20}}, "
                      "got {}",
                      v.dump()));
    case ValueKind::kColumns:
      return columns(v);
    case ValueKind::kText:
      if (v.is_string() && !v.get<std::string>().empty()) return v;
      throw std::invalid_argument(fmt::format("expected a non-empty string, got {}", v.dump()));
    case ValueKind::kFolder:
    case ValueKind::kRunFolder:
    case ValueKind::kFlag:
      break;  // out, resume and quiet: the sweep's own (sweep_owned)
  }
  throw std::invalid_argument(fmt::format("--{} is not a sweep key", key.name));
}

const std::vector<const TrainOption*>& key_table() {
  static const std::vector<const TrainOption*> keys = [] {
    std::vector<const TrainOption*> k;
    for (const TrainOption& option : tasks::train_options())
      if (option.sweep_owned.empty()) k.push_back(&option);
    std::sort(k.begin(), k.end(), [](const TrainOption* a, const TrainOption* b) {
      return a->sweep_rank < b->sweep_rank;
    });
    return k;
  }();
  return keys;
}

const TrainOption* find_key(std::string_view name) {
  const TrainOption* option = tasks::find_train_option(name);
  return option != nullptr && option->sweep_owned.empty() ? option : nullptr;
}

std::string_view sweep_owned(std::string_view name) {
  const TrainOption* option = tasks::find_train_option(name);
  return option == nullptr ? std::string_view() : option->sweep_owned;
}

std::vector<std::string> spec_keys() {
  std::vector<std::string> names;
  for (const TrainOption* k : key_table()) names.emplace_back(k->name);
  return names;
}

// How a value reads in `hnn train`'s arguments.
std::vector<std::string> arg_values(const TrainOption& key, const ordered_json& v) {
  switch (key.kind) {
    case ValueKind::kHidden: {
      std::vector<std::string> widths;
      for (const ordered_json& w : v) widths.push_back(w.dump());
      return widths;
    }
    case ValueKind::kColumns:
      return {fmt::format("{}", fmt::join(v.get<std::vector<std::string>>(), ","))};
    case ValueKind::kJsonObject:
      return {v.dump()};
    default:
      return {v.is_string() ? v.get<std::string>() : number_text(v)};
  }
}

std::string name_value(const TrainOption& key, const ordered_json& v) {
  switch (key.kind) {
    case ValueKind::kHidden:
      return tasks::join_widths(v.get<std::vector<int>>());
    case ValueKind::kFile:
      return folder_safe(fs::path(v.get<std::string>()).filename().string());
    case ValueKind::kColumns:
      return folder_safe(fmt::format("{}", fmt::join(v.get<std::vector<std::string>>(), "+")));
    case ValueKind::kJsonObject:
      return folder_safe(v.dump());
    default:
      return folder_safe(v.is_string() ? v.get<std::string>() : number_text(v));
  }
}

}  // namespace hnn::app::sweep
