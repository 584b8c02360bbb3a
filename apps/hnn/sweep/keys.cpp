// The spec's keys, `hnn train`'s options: each value checked, written as `hnn train`
// arguments and in run folder names, and applied to tasks::RunOptions.

#include "apps/hnn/sweep/keys.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "apps/hnn/commands/validators.h"
#include "tasks/experiments/registry.h"
#include "tasks/task.h"

namespace hnn::app::sweep {

namespace fs = std::filesystem;
using nlohmann::json;
using nlohmann::ordered_json;

namespace {

// `hnn train`'s options, in the canonical order of run names and table columns.
constexpr KeyInfo kKeys[] = {
    {"task", Kind::kTask},
    {"model", Kind::kModel},
    {"seed", Kind::kSeed},
    {"dtype", Kind::kDtype},
    {"preset", Kind::kPreset},
    {"hidden", Kind::kHidden},
    {"steps", Kind::kPositiveInt},
    {"batch", Kind::kNonNegativeInt},
    {"lr", Kind::kPositiveReal},
    {"lr-schedule", Kind::kLrSchedule},
    {"data", Kind::kFile},
    {"settings", Kind::kObject},
    {"checkpoint-every", Kind::kPositiveInt},
    {"coords", Kind::kColumns, "coords"},
    {"momenta", Kind::kColumns, "momenta"},
    {"velocities", Kind::kColumns, "velocities"},
    {"derivatives", Kind::kColumns, "derivatives"},
    {"time", Kind::kText, "time"},
    {"trajectory", Kind::kText, "trajectory"},
    {"split", Kind::kSplit, "split"},
    {"test-fraction", Kind::kFraction, "test_fraction"},
    {"hamiltonian", Kind::kText, "hamiltonian"},
    {"loss", Kind::kLoss, "loss"},
    {"horizon", Kind::kPositiveInt, "horizon"},
    {"integrator", Kind::kText, "integrator"},
};

// Options of `hnn train` that the sweep sets itself.
const std::map<std::string_view, std::string_view> kSweepOwned = {
    {"threads", "set by hnn sweep for every run (--threads-per-run)"},
    {"out", "set by hnn sweep (OUT/runs/<run>)"},
    {"resume", "hnn sweep resumes interrupted runs by itself"},
    {"quiet", "hnn sweep runs quietly"}};

std::invalid_argument bad(std::string message) { return std::invalid_argument(message); }

std::string one_of(const ordered_json& v, const std::vector<std::string>& names,
                   std::string_view what) {
  if (v.is_string() && std::find(names.begin(), names.end(), v.get<std::string>()) != names.end())
    return v.get<std::string>();
  if (v.is_string())
    throw bad(fmt::format("unknown {} '{}' (known: {})", what, v.get<std::string>(),
                          fmt::join(names, ", ")));
  throw bad(fmt::format("expected a {} ({}), got {}", what, fmt::join(names, ", "), v.dump()));
}

long long integer_in(const ordered_json& v, long long min, long long max) {
  if (v.is_number_integer()) {
    const bool fits =
        v.is_number_unsigned()
            ? v.get<unsigned long long>() >= static_cast<unsigned long long>(std::max(min, 0LL)) &&
                  v.get<unsigned long long>() <= static_cast<unsigned long long>(max)
            : v.get<long long>() >= min && v.get<long long>() <= max;
    if (fits) return v.get<long long>();
  }
  if (max == std::numeric_limits<int>::max())
    throw bad(fmt::format("expected an integer >= {}, got {}", min, v.dump()));
  throw bad(fmt::format("expected an integer from {} to {}, got {}", min, max, v.dump()));
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
    throw bad(
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

}  // namespace

// The value in its canonical form (hidden as a list, a file as an absolute path, ...), or
// std::invalid_argument saying what was expected.
ordered_json checked_value(const KeyInfo& key, const ordered_json& v) {
  switch (key.kind) {
    case Kind::kTask:
      return one_of(v, tasks::task_names(), "task");
    case Kind::kModel:
      return one_of(v, tasks::model_names(), "model");
    case Kind::kDtype:
      return one_of(v, tasks::dtype_names(), "dtype");
    case Kind::kPreset:
      return one_of(v, tasks::preset_names(), "preset");
    case Kind::kSplit:
      return one_of(v, {"auto", "trajectories", "time"}, "split");
    case Kind::kLrSchedule:
      return one_of(v, {"constant", "cosine"}, "learning-rate schedule");
    case Kind::kLoss:
      return one_of(v, loss_names(), "loss");
    case Kind::kSeed:
      if (v.is_number_unsigned()) return v;
      throw bad(
          fmt::format("expected an integer from 0 to 18446744073709551615, got {}", v.dump()));
    case Kind::kPositiveInt:
      return integer_in(v, 1, std::numeric_limits<int>::max());
    case Kind::kNonNegativeInt:
      return integer_in(v, 0, std::numeric_limits<int>::max());
    case Kind::kHidden: {
      ordered_json widths = ordered_json::array();
      for (const ordered_json& w : v.is_array() ? v : ordered_json::array({v})) {
        try {
          widths.push_back(integer_in(w, 1, tasks::kMaxWidth));
        } catch (const std::invalid_argument&) {
          throw bad(fmt::format("expected hidden widths of 1..{}, as [200, 200] or 64, got {}",
                                tasks::kMaxWidth, v.dump()));
        }
      }
      if (widths.empty()) throw bad("expected at least one hidden width, got []");
      return widths;
    }
    case Kind::kPositiveReal:
      if (v.is_number() && std::isfinite(v.get<double>()) && v.get<double>() > 0) return v;
      throw bad(fmt::format("expected a finite number > 0, got {}", v.dump()));
    case Kind::kFraction:
      if (v.is_number() && v.get<double>() > 0 && v.get<double>() < 1) return v;
      throw bad(fmt::format("expected a number in (0, 1), got {}", v.dump()));
    case Kind::kFile:
      if (v.is_string() && !v.get<std::string>().empty())
        return fs::absolute(v.get<std::string>()).lexically_normal().string();
      throw bad(fmt::format("expected a file name, got {}", v.dump()));
    case Kind::kObject:
      if (v.is_object()) return v;
      throw bad(
          fmt::format("expected the task's settings as an object, like {{\"trials\": 20}}, "
                      "got {}",
                      v.dump()));
    case Kind::kColumns:
      return columns(v);
    case Kind::kText:
      if (v.is_string() && !v.get<std::string>().empty()) return v;
      throw bad(fmt::format("expected a non-empty string, got {}", v.dump()));
  }
  throw bad("unhandled key");
}

std::span<const KeyInfo> key_table() { return kKeys; }

const KeyInfo* find_key(std::string_view name) {
  for (const KeyInfo& k : kKeys)
    if (k.name == name) return &k;
  return nullptr;
}

std::string_view sweep_owned(std::string_view name) {
  const auto it = kSweepOwned.find(name);
  return it == kSweepOwned.end() ? std::string_view() : it->second;
}

std::vector<std::string> spec_keys() {
  std::vector<std::string> names;
  for (const KeyInfo& k : kKeys) names.emplace_back(k.name);
  return names;
}

// How a value reads in `hnn train`'s arguments.
std::vector<std::string> arg_values(const KeyInfo& key, const ordered_json& v) {
  switch (key.kind) {
    case Kind::kHidden: {
      std::vector<std::string> widths;
      for (const ordered_json& w : v) widths.push_back(w.dump());
      return widths;
    }
    case Kind::kColumns:
      return {fmt::format("{}", fmt::join(v.get<std::vector<std::string>>(), ","))};
    case Kind::kObject:
      return {v.dump()};
    default:
      return {v.is_string() ? v.get<std::string>() : number_text(v)};
  }
}

std::string name_value(const KeyInfo& key, const ordered_json& v) {
  switch (key.kind) {
    case Kind::kHidden:
      return tasks::join_widths(v.get<std::vector<int>>());
    case Kind::kFile:
      return folder_safe(fs::path(v.get<std::string>()).filename().string());
    case Kind::kColumns:
      return folder_safe(fmt::format("{}", fmt::join(v.get<std::vector<std::string>>(), "+")));
    case Kind::kObject:
      return folder_safe(v.dump());
    default:
      return folder_safe(v.is_string() ? v.get<std::string>() : number_text(v));
  }
}

void apply_value(const KeyInfo& key, const ordered_json& v, tasks::RunOptions& o) {
  switch (key.kind) {
    case Kind::kModel:
      o.model = tasks::parse_model(v.get<std::string>());
      break;
    case Kind::kSeed:
      o.seed = v.get<std::uint64_t>();
      break;
    case Kind::kDtype:
      o.dtype = tasks::parse_dtype(v.get<std::string>());
      break;
    case Kind::kPreset:
      o.preset = tasks::parse_preset(v.get<std::string>());
      break;
    case Kind::kHidden:
      o.hidden = v.get<std::vector<int>>();
      break;
    case Kind::kFile:
      o.data_file = v.get<std::string>();
      break;
    case Kind::kObject:
      o.task_settings = json::parse(v.dump());
      break;
    case Kind::kPositiveReal:
      o.learning_rate = v.get<double>();
      break;
    case Kind::kLrSchedule:
      o.lr_schedule = tasks::parse_lr_schedule(v.get<std::string>());
      break;
    default:
      if (key.name == "steps") o.steps = v.get<int>();
      if (key.name == "batch") o.batch_size = v.get<int>();
      if (key.name == "checkpoint-every") o.checkpoint_every = v.get<long>();
  }
}

}  // namespace hnn::app::sweep
