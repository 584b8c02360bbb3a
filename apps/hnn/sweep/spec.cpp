// `hnn sweep`'s spec, read (JSON, or YAML through yaml-cpp), checked key by key and expanded to
// the runs of its grids, each checked as `hnn train` would check it (tasks::validate).

#include "apps/hnn/sweep/spec.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "apps/hnn/sweep/keys.h"
#include "tasks/options.h"
#include "tasks/options/fit_options.h"
#include "tasks/run.h"

namespace hnn::app::sweep {

namespace fs = std::filesystem;
using nlohmann::json;
using nlohmann::ordered_json;

namespace {

std::invalid_argument bad(std::string message) { return std::invalid_argument(message); }

// ---- grids ---------------------------------------------------------------------------------

using tasks::TrainOption;

struct Axis {
  const TrainOption* key;
  std::vector<ordered_json> values;
};

std::string known_keys() { return fmt::format("{}", fmt::join(spec_keys(), ", ")); }

// One grid's keys, checked, in the file's order (the first key varies slowest).
std::vector<Axis> axes_of(const ordered_json& grid) {
  std::vector<Axis> axes;
  for (const auto& item : grid.items()) {
    const std::string& name = item.key();
    const ordered_json& values = item.value();
    const auto prefix = [&](const std::string& what) {
      return bad(fmt::format("key '{}': {}", name, what));
    };
    if (const std::string_view why = sweep_owned(name); !why.empty())
      throw prefix(std::string(why));
    const TrainOption* key = find_key(name);
    if (key == nullptr) {
      throw prefix(fmt::format("not an option of hnn train (the spec's keys: {}; grids, charts)",
                               known_keys()));
    }
    if (!values.is_array()) {
      throw prefix(fmt::format("expected a list of values to cross, like [{}], got {}",
                               values.dump(), values.dump()));
    }
    if (values.empty()) throw prefix("an empty list: the grid would have no runs");
    Axis axis{key, {}};
    for (const ordered_json& v : values) {
      try {
        axis.values.push_back(checked_value(*key, v));
      } catch (const std::invalid_argument& e) {
        throw prefix(e.what());
      }
      if (std::count(axis.values.begin(), axis.values.end(), axis.values.back()) > 1) {
        throw prefix(fmt::format("the value {} is listed twice{}", v.dump(),
                                 key->kind == tasks::ValueKind::kHidden
                                     ? " (one value per model: [[16, 16]] is one 16-16 model)"
                                     : ""));
      }
    }
    axes.push_back(std::move(axis));
  }
  if (std::none_of(axes.begin(), axes.end(), [](const Axis& a) { return a.key->name == "task"; }))
    throw bad("key 'task': missing (every run needs a task, like \"task\": [\"spring\"])");
  return axes;
}

// The spec's grids: the spec itself, its list of grids, or its "grids" each crossed with the
// keys beside them.
std::vector<ordered_json> grids_of(const ordered_json& spec) {
  if (spec.is_array()) {
    if (spec.empty()) throw bad("an empty list of grids: no runs");
    for (const ordered_json& g : spec)
      if (!g.is_object())
        throw bad(fmt::format("expected each grid to be an object, got {}", g.dump()));
    return {spec.begin(), spec.end()};
  }
  if (!spec.is_object()) {
    throw bad(
        fmt::format("expected an object of hnn train's option names to lists of values, "
                    "like {{\"task\": [\"spring\"], \"seed\": [0, 1]}}, got {}",
                    spec.dump().substr(0, 60)));
  }
  ordered_json shared = spec;
  shared.erase("charts");
  if (!spec.contains("grids")) {
    if (shared.empty()) throw bad("no keys: the spec needs at least \"task\": [...]");
    return {shared};
  }
  shared.erase("grids");
  const ordered_json& grids = spec["grids"];
  if (!grids.is_array() || grids.empty())
    throw bad(fmt::format("key 'grids': expected a non-empty list of grids, got {}", grids.dump()));
  std::vector<ordered_json> out;
  for (const ordered_json& g : grids) {
    if (!g.is_object())
      throw bad(fmt::format("key 'grids': expected each grid to be an object, got {}", g.dump()));
    ordered_json merged = shared;
    for (const auto& [name, values] : g.items()) {
      if (merged.contains(name))
        throw bad(fmt::format("key '{}': given both beside \"grids\" and in grid {}", name,
                              out.size() + 1));
      merged[name] = values;
    }
    out.push_back(merged);
  }
  return out;
}

// ---- runs ----------------------------------------------------------------------------------

// FNV-1a: a stable short tag for names that would collide or run long.
std::string hash_tag(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return fmt::format("{:08x}", std::uint32_t(h ^ (h >> 32)));
}

// One combination of values as `hnn train` options, arguments, and a folder name.
SweepRun build_run(const std::vector<std::pair<const TrainOption*, ordered_json>>& chosen,
                   const fs::path& out, tasks::RunOptions& o) {
  std::map<std::string_view, ordered_json> by_name;
  for (const auto& [key, v] : chosen) by_name[key->name] = v;
  SweepRun run;
  o.task = by_name.at("task").get<std::string>();
  run.args = {o.task};
  std::vector<std::string> tags;
  for (const TrainOption* key : key_table()) {
    if (!by_name.count(key->name)) continue;
    const ordered_json& v = by_name.at(key->name);
    run.values[std::string(key->name)] = v;
    if (key->name == "task") continue;
    run.args.push_back("--" + std::string(key->name));
    for (std::string& a : arg_values(*key, v)) run.args.push_back(std::move(a));
    if (key->name != "model") tags.push_back(fmt::format("{}={}", key->name, name_value(*key, v)));
    if (const std::string why = tasks::not_applicable(*key, o.task); !why.empty())
      throw bad(fmt::format("key '{}': {}", key->name, why));
    tasks::apply(*key, json::parse(v.dump()), o);
  }
  std::string rest = tags.empty() ? "default" : fmt::format("{}", fmt::join(tags, ","));
  if (rest.size() > 160) rest = "h" + hash_tag(rest);
  run.name = fmt::format("{}/{}/{}", o.task, nn::to_string(o.model), rest);
  o.out = out / "runs" / run.name;
  return run;
}

// A sampled fit takes no steps: a grid that crosses --fit with --steps (say) asks its sampled
// runs for steps, which hnn train refuses. Said as the spec's mistake, with the way out.
void check_sampled_grid(const tasks::RunOptions& o, const std::string& name,
                        const std::string& where) {
  if (o.task_settings.value("fit", "") != "sampled") return;
  if (const char* option = tasks::adam_option_given(o)) {
    throw bad(fmt::format(
        "{}: run '{}': {} does not apply to --fit sampled (it takes no training steps): put the "
        "sampled runs in a grid of their own, without {} (a union of grids, docs/sweeps.md)",
        where, name, option, option));
  }
}

// Every combination of the axes' values, the first axis slowest.
template <typename F>
void for_each_combination(const std::vector<Axis>& axes, F&& f) {
  std::vector<std::size_t> at(axes.size(), 0);
  while (true) {
    std::vector<std::pair<const TrainOption*, ordered_json>> chosen;
    for (std::size_t i = 0; i < axes.size(); ++i)
      chosen.emplace_back(axes[i].key, axes[i].values[at[i]]);
    f(chosen);
    std::size_t i = axes.size();
    while (i > 0 && ++at[i - 1] == axes[i - 1].values.size()) at[--i] = 0;
    if (i == 0) return;
  }
}

json checked_charts(const ordered_json& spec, const std::set<std::string>& keys) {
  if (!spec.is_object() || !spec.contains("charts")) return json::array();
  const ordered_json& charts = spec["charts"];
  const auto fail = [](std::size_t i, const std::string& what) {
    return bad(fmt::format("key 'charts': chart {}: {}", i + 1, what));
  };
  if (!charts.is_array())
    throw bad(fmt::format("key 'charts': expected a list of charts, got {}", charts.dump()));
  json out = json::array();
  for (std::size_t i = 0; i < charts.size(); ++i) {
    const ordered_json& c = charts[i];
    if (!c.is_object() || c.contains("x") == c.contains("x_metric") || !c.contains("y"))
      throw fail(i, fmt::format("expected an object with \"y\" and one of \"x\" (a spec key) "
                                "or \"x_metric\" (a metric), got {}",
                                c.dump()));
    for (const auto& [k, v] : c.items()) {
      if (k == "x" || k == "series" || k == "facet") {
        if (!v.is_string() || !keys.count(v.get<std::string>()))
          throw fail(i, fmt::format("'{}' must be one of the spec's keys ({}), got {}", k,
                                    fmt::join(keys, ", "), v.dump()));
      } else if (k == "y" || k == "x_metric" || k == "title" || k == "file") {
        if (!v.is_string() || v.get<std::string>().empty())
          throw fail(i, fmt::format("'{}' must be a non-empty string, got {}", k, v.dump()));
        if (k == "file" && v.get<std::string>().find('/') != std::string::npos)
          throw fail(i, fmt::format("'file' is a file name in OUT, not a path, got {}", v.dump()));
      } else if (k == "where") {
        if (!v.is_object())
          throw fail(i, fmt::format("'where' must be an object, got {}", v.dump()));
        for (const auto& [wk, wv] : v.items()) {
          if (!keys.count(wk))
            throw fail(i, fmt::format("'where' key '{}' is not one of the spec's keys ({})", wk,
                                      fmt::join(keys, ", ")));
          if (!wv.is_array() || wv.empty())
            throw fail(
                i, fmt::format("'where' key '{}' needs a list of values, got {}", wk, wv.dump()));
        }
      } else if (k == "log_x" || k == "log_y") {
        if (!v.is_boolean())
          throw fail(i, fmt::format("'{}' must be true or false, got {}", k, v.dump()));
      } else {
        throw fail(i, fmt::format("unknown key '{}' (x, x_metric, y, series, facet, where, log_x, "
                                  "log_y, title, file)",
                                  k));
      }
    }
    out.push_back(json::parse(c.dump()));
  }
  return out;
}

// ---- YAML ----------------------------------------------------------------------------------

// A plain YAML scalar as JSON would type it: integer, number, true/false, null, else a string.
ordered_json yaml_scalar(const YAML::Node& node) {
  const std::string& s = node.Scalar();
  if (node.Tag() == "!") return s;  // quoted: always a string
  const char* end = s.data() + s.size();
  long long i = 0;
  if (auto [p, ec] = std::from_chars(s.data(), end, i); ec == std::errc() && p == end)
    return i >= 0 ? ordered_json(static_cast<unsigned long long>(i)) : ordered_json(i);
  double d = 0;
  if (auto [p, ec] = std::from_chars(s.data(), end, d); ec == std::errc() && p == end && !s.empty())
    return d;
  if (s == "true" || s == "True" || s == "TRUE") return true;
  if (s == "false" || s == "False" || s == "FALSE") return false;
  if (s == "null" || s == "~" || s.empty()) return nullptr;
  return s;
}

ordered_json from_yaml(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Sequence: {
      ordered_json a = ordered_json::array();
      for (const YAML::Node& item : node) a.push_back(from_yaml(item));
      return a;
    }
    case YAML::NodeType::Map: {
      ordered_json o = ordered_json::object();
      for (const auto& kv : node) o[kv.first.Scalar()] = from_yaml(kv.second);
      return o;
    }
    case YAML::NodeType::Scalar:
      return yaml_scalar(node);
    default:
      return nullptr;
  }
}

}  // namespace

ordered_json read_spec(const fs::path& file) {
  const std::string where = fmt::format("sweep spec {}", file.string());
  std::ifstream in(file);
  if (!in) throw bad(fmt::format("{}: cannot be read", where));
  std::stringstream text;
  text << in.rdbuf();
  const std::string ext = file.extension().string();
  try {
    if (ext == ".yaml" || ext == ".yml") return from_yaml(YAML::Load(text.str()));
    return ordered_json::parse(text.str());
  } catch (const YAML::Exception& e) {
    throw bad(fmt::format("{}: not valid YAML: {}", where, e.what()));
  } catch (const ordered_json::parse_error& e) {
    std::string message = e.what();
    if (const auto p = message.find("] "); p != std::string::npos) message = message.substr(p + 2);
    throw bad(fmt::format("{}: not valid JSON ({} for YAML): {}", where, ".yaml/.yml", message));
  }
}

SweepPlan expand(const ordered_json& spec, const std::string& where, const fs::path& out) {
  SweepPlan plan;
  std::vector<ordered_json> grids;
  try {
    grids = grids_of(spec);
  } catch (const std::invalid_argument& e) {
    throw bad(fmt::format("{}: {}", where, e.what()));
  }
  std::set<std::string> used_keys, seen_settings;
  std::vector<tasks::RunOptions> options;
  for (std::size_t g = 0; g < grids.size(); ++g) {
    const std::string grid_where =
        grids.size() > 1 ? fmt::format("{}: grid {}", where, g + 1) : where;
    std::vector<Axis> axes;
    try {
      axes = axes_of(grids[g]);
    } catch (const std::invalid_argument& e) {
      throw bad(fmt::format("{}: {}", grid_where, e.what()));
    }
    for (const Axis& a : axes) used_keys.insert(std::string(a.key->name));
    for_each_combination(axes, [&](const auto& chosen) {
      tasks::RunOptions o;
      SweepRun run;
      try {
        run = build_run(chosen, out, o);
      } catch (const std::exception& e) {
        throw bad(fmt::format("{}: {}", grid_where, e.what()));
      }
      check_sampled_grid(o, run.name, grid_where);
      try {
        run.settings = tasks::validate(o).to_json();
      } catch (const std::exception& e) {
        throw bad(fmt::format("{}: run '{}': {}", grid_where, run.name, e.what()));
      }
      run.settings.erase("threads");                                  // the sweep's, not the run's
      if (!seen_settings.insert(run.settings.dump()).second) return;  // in an earlier grid
      plan.runs.push_back(std::move(run));
    });
  }
  // Distinct runs that read alike (files of one name in two folders, say) get a tag each.
  std::map<std::string, int> count;
  for (const SweepRun& r : plan.runs) ++count[r.name];
  for (SweepRun& r : plan.runs)
    if (count[r.name] > 1) r.name += "~" + hash_tag(r.settings.dump());
  for (const TrainOption* k : key_table())
    if (used_keys.count(std::string(k->name))) plan.keys.emplace_back(k->name);
  try {
    plan.charts = checked_charts(spec, used_keys);
  } catch (const std::invalid_argument& e) {
    throw bad(fmt::format("{}: {}", where, e.what()));
  }
  return plan;
}

}  // namespace hnn::app::sweep
