// Choosing columns, grouping rows into trajectories, cutting them at gaps, and dx/dt.
#include "tasks/data/measured_trajectories.h"

#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "tasks/error.h"

namespace hnn::tasks {

namespace {

// The resolved choice: column indices into the table.
struct Columns {
  Eigen::Index time = -1, trajectory = -1;
  std::vector<Eigen::Index> coords, momenta, derivatives;
  bool velocities = false;
};

Eigen::Index first_present(const Table& table, std::initializer_list<const char*> names) {
  for (const char* name : names) {
    if (const Eigen::Index j = table.find(name); j >= 0) return j;
  }
  return -1;
}

std::vector<Eigen::Index> resolve(const Table& table, const std::vector<std::string>& choices) {
  std::vector<Eigen::Index> out;
  for (const std::string& c : choices) {
    const std::vector<Eigen::Index> columns = table.columns_of(c);
    out.insert(out.end(), columns.begin(), columns.end());
  }
  return out;
}

std::string names_of(const Table& table, const std::vector<Eigen::Index>& columns) {
  std::string text;
  for (Eigen::Index j : columns) text += (text.empty() ? "" : ", ") + table.names[std::size_t(j)];
  return text;
}

// A Lipson file's default: the first half of its header's columns are coordinates, the second
// half their velocities.
void lipson_state(const Table& table, Columns& c) {
  const std::size_t named = table.header_state.size();
  HNN_TASKS_CHECK(named % 2 == 0,
                  "{}: the '%' header names {} state columns ({}), which do not halve into "
                  "coordinates and velocities: give coords and velocities",
                  table.source, named, fmt::join(table.header_state, " "));
  for (std::size_t k = 0; k < named; ++k) {
    (k < named / 2 ? c.coords : c.momenta).push_back(table.find(table.header_state[k]));
  }
  c.velocities = true;
}

void resolve_state(const Table& table, const ColumnChoice& choice, Columns& c) {
  if (choice.coords.empty() && choice.momenta.empty() && choice.velocities.empty() &&
      !table.header_state.empty()) {
    return lipson_state(table, c);
  }
  HNN_TASKS_CHECK(!choice.coords.empty(),
                  "{}: which columns are the coordinates? give coords, and momenta or velocities "
                  "(columns: {})",
                  table.source, fmt::join(table.names, ", "));
  HNN_TASKS_CHECK(choice.momenta.empty() != choice.velocities.empty(),
                  "{}: give either momenta or velocities for the coordinates {}", table.source,
                  choice.momenta.empty() ? "(neither was given)" : "(not both)");
  c.coords = resolve(table, choice.coords);
  c.velocities = !choice.velocities.empty();
  c.momenta = resolve(table, c.velocities ? choice.velocities : choice.momenta);
  const char* what = c.velocities ? "velocities" : "momenta";
  HNN_TASKS_CHECK(c.coords.size() == c.momenta.size(),
                  "{}: {} coordinates ({}) but {} {} ({}): each coordinate needs one", table.source,
                  c.coords.size(), names_of(table, c.coords), c.momenta.size(), what,
                  names_of(table, c.momenta));
}

// No column may play two parts (a coordinate that is also the time, ...).
void check_distinct(const Table& table, const Columns& c) {
  std::map<Eigen::Index, std::string> part;
  const auto claim = [&](Eigen::Index j, const std::string& as) {
    if (j < 0) return;
    const auto [it, fresh] = part.emplace(j, as);
    HNN_TASKS_CHECK(fresh, "{}: column '{}' is chosen twice (as {} and as {})", table.source,
                    table.names[std::size_t(j)], it->second, as);
  };
  claim(c.time, "the time");
  claim(c.trajectory, "the trajectory id");
  for (Eigen::Index j : c.coords) claim(j, "a coordinate");
  for (Eigen::Index j : c.momenta) claim(j, c.velocities ? "a velocity" : "a momentum");
  for (Eigen::Index j : c.derivatives) claim(j, "a derivative");
}

// The names a derivative column of `name` may have: d<name>/dt (what `hnn simulate` writes),
// d<name>dt, d<name>_dt, <name>_dot, and in an .npz d<name> (as dx beside x); an npz array's
// column "x[1]" looks for "dx/dt[1]", ... "dx[1]".
std::vector<std::string> derivative_names(const Table& table, const std::string& name) {
  const std::size_t bracket = name.find('[');
  const bool part = table.format == TableFormat::kNpz && bracket != std::string::npos;
  const std::string base = part ? name.substr(0, bracket) : name;
  const std::string index = part ? name.substr(bracket) : "";
  std::vector<std::string> out = {"d" + base + "/dt", "d" + base + "dt", "d" + base + "_dt",
                                  base + "_dot"};
  if (table.format == TableFormat::kNpz) out.push_back("d" + base);
  for (std::string& candidate : out) candidate += index;
  return out;
}

// Derivative columns found by name for every state column, or none (with what was missing in
// `note`): a column already chosen for another part is not one.
std::vector<Eigen::Index> find_derivatives(const Table& table, const Columns& c,
                                           std::string& note) {
  std::vector<Eigen::Index> state = c.coords, found;
  state.insert(state.end(), c.momenta.begin(), c.momenta.end());
  std::vector<std::string> missing;
  for (Eigen::Index j : state) {
    Eigen::Index hit = -1;
    for (const std::string& candidate : derivative_names(table, table.names[std::size_t(j)])) {
      const Eigen::Index k = table.find(candidate);
      const bool taken = k == c.time || k == c.trajectory ||
                         std::find(state.begin(), state.end(), k) != state.end();
      if (k >= 0 && !taken) {
        hit = k;
        break;
      }
    }
    if (hit >= 0) found.push_back(hit);
    if (hit < 0) missing.push_back(table.names[std::size_t(j)]);
  }
  if (missing.empty()) return found;
  if (!found.empty()) {
    note = fmt::format("derivative columns {} found, none for {}: --derivatives names them all",
                       names_of(table, found), fmt::join(missing, ", "));
  }
  return {};
}

// Without a time column the rows are scattered states, which need their dx/dt from columns
// and cannot have trajectories.
void check_scattered(const Table& table, const Columns& c, const std::string& note) {
  HNN_TASKS_CHECK(!c.derivatives.empty(),
                  "{}: no time column (none is named t, time or times) and no derivative columns"
                  "{}: give the time column by name or index, or for scattered states dx/dt of "
                  "every state column (named d<x>/dt, or chosen with --derivatives) (columns: {})",
                  table.source, note.empty() ? "" : " (" + note + ")",
                  fmt::join(table.names, ", "));
  HNN_TASKS_CHECK(c.trajectory < 0,
                  "{}: a trajectory column ('{}') but no time column (none is named t, time or "
                  "times): give the time column, or drop the trajectory column for scattered "
                  "states",
                  table.source, table.names[std::size_t(c.trajectory)]);
}

Columns resolve_columns(const Table& table, const ColumnChoice& choice, std::string& note) {
  Columns c;
  c.time = choice.time.empty() ? first_present(table, {"t", "time", "times"})
                               : table.column(choice.time);
  c.trajectory = choice.trajectory.empty() ? first_present(table, {"trajectory", "trial"})
                                           : table.column(choice.trajectory);
  resolve_state(table, choice, c);
  const bool differences = choice.derivatives == std::vector<std::string>{"none"} &&
                           table.find("none") < 0;  // --derivatives none
  c.derivatives = differences ? std::vector<Eigen::Index>{} : resolve(table, choice.derivatives);
  if (choice.derivatives.empty()) c.derivatives = find_derivatives(table, c, note);
  if (differences) note = "--derivatives none";
  HNN_TASKS_CHECK(c.derivatives.empty() || c.derivatives.size() == 2 * c.coords.size(),
                  "{}: {} derivative columns ({}) for a state of {}: give dx/dt of every "
                  "coordinate, then of every {}",
                  table.source, c.derivatives.size(), names_of(table, c.derivatives),
                  2 * c.coords.size(), c.velocities ? "velocity" : "momentum");
  check_distinct(table, c);
  if (c.time < 0) check_scattered(table, c, note);
  return c;
}

// Rows by trajectory id, ids in order of first appearance, rows in file order.
std::vector<std::pair<double, std::vector<Eigen::Index>>> group_rows(const Table& table,
                                                                     Eigen::Index id_column) {
  std::vector<std::pair<double, std::vector<Eigen::Index>>> groups;
  std::map<double, std::size_t> slot;
  for (Eigen::Index i = 0; i < table.rows(); ++i) {
    const double id = id_column < 0 ? 0.0 : table.values(i, id_column);
    const auto [it, fresh] = slot.emplace(id, groups.size());
    if (fresh) groups.push_back({id, {}});
    groups[it->second].second.push_back(i);
  }
  return groups;
}

void check_trajectory(const Table& table, const Columns& c, double id,
                      const std::vector<Eigen::Index>& rows) {
  const std::string name =
      c.trajectory < 0 ? "the file's one trajectory" : fmt::format("trajectory {}", id);
  HNN_TASKS_CHECK(rows.size() >= 3, "{}: {} has {} point{}; at least 3 are needed",
                  table.where(rows[0]), name, rows.size(), rows.size() == 1 ? "" : "s");
  for (std::size_t k = 1; k < rows.size(); ++k) {
    const double before = table.values(rows[k - 1], c.time), now = table.values(rows[k], c.time);
    HNN_TASKS_CHECK(now > before, "{}: time does not increase within {} (t = {} then {})",
                    table.where(rows[k]), name, before, now);
  }
}

// Cuts where a step exceeds `factor` times the median step.
std::vector<std::vector<Eigen::Index>> cut_at_gaps(const Table& table, Eigen::Index time,
                                                   const std::vector<Eigen::Index>& rows,
                                                   double factor) {
  std::vector<double> steps;
  for (std::size_t k = 1; k < rows.size(); ++k) {
    steps.push_back(table.values(rows[k], time) - table.values(rows[k - 1], time));
  }
  std::vector<double> sorted = steps;
  std::nth_element(sorted.begin(), sorted.begin() + long(sorted.size() / 2), sorted.end());
  const double limit = factor > 0 ? factor * sorted[sorted.size() / 2] : INFINITY;
  std::vector<std::vector<Eigen::Index>> pieces(1, {rows[0]});
  for (std::size_t k = 1; k < rows.size(); ++k) {
    if (steps[k - 1] > limit) pieces.emplace_back();
    pieces.back().push_back(rows[k]);
  }
  return pieces;
}

Segment make_segment(const Table& table, const Columns& c, double id,
                     std::vector<Eigen::Index> rows) {
  std::vector<Eigen::Index> state = c.coords;
  state.insert(state.end(), c.momenta.begin(), c.momenta.end());
  const auto idx = [](const std::vector<Eigen::Index>& v) {
    return Eigen::Map<const Eigen::Matrix<Eigen::Index, Eigen::Dynamic, 1>>(v.data(),
                                                                            Eigen::Index(v.size()));
  };
  Segment s{id, std::move(rows), {}, {}, {}};
  if (c.time >= 0) s.t = table.values(idx(s.rows), c.time);
  s.x = table.values(idx(s.rows), idx(state));
  s.dxdt = c.derivatives.empty() ? finite_differences(s.t, s.x)
                                 : Batch(table.values(idx(s.rows), idx(c.derivatives)));
  return s;
}

// A file without a time column: its rows as one segment of states with no times.
MeasuredTrajectories scattered_states(Table table, const Columns& c, MeasuredTrajectories out) {
  std::vector<Eigen::Index> rows(std::size_t(table.rows()));
  for (Eigen::Index i = 0; i < table.rows(); ++i) rows[std::size_t(i)] = i;
  out.scattered = true;
  out.segments.push_back(make_segment(table, c, 0.0, std::move(rows)));
  out.table = std::move(table);
  return out;
}

// The three Lagrange weights of the derivative at `at` through the points a, b, c.
std::array<double, 3> derivative_weights(double a, double b, double c, double at) {
  return {(2 * at - b - c) / ((a - b) * (a - c)), (2 * at - a - c) / ((b - a) * (b - c)),
          (2 * at - a - b) / ((c - a) * (c - b))};
}

}  // namespace

Batch finite_differences(const Eigen::VectorXd& t, const Batch& x) {
  const Eigen::Index n = t.size();
  HNN_TASKS_CHECK(n >= 3 && x.rows() == n,
                  "finite_differences: {} times for {} states; at least "
                  "3 of each are needed",
                  n, x.rows());
  Batch dxdt(n, x.cols());
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index first = std::clamp<Eigen::Index>(i - 1, 0, n - 3);  // one-sided at the ends
    const auto w = derivative_weights(t(first), t(first + 1), t(first + 2), t(i));
    dxdt.row(i) = w[0] * x.row(first) + w[1] * x.row(first + 1) + w[2] * x.row(first + 2);
  }
  return dxdt;
}

MeasuredTrajectories select_trajectories(Table table, const ColumnChoice& choice) {
  HNN_TASKS_CHECK(
      choice.gap_factor == 0 || (choice.gap_factor > 1 && std::isfinite(choice.gap_factor)),
      "gap factor {} is neither 0 (never cut) nor a finite number > 1", choice.gap_factor);
  MeasuredTrajectories out;
  const Columns c = resolve_columns(table, choice, out.derivatives_note);
  out.coordinates = Eigen::Index(c.coords.size());
  for (const auto* part : {&c.coords, &c.momenta}) {
    for (Eigen::Index j : *part) out.state_names.push_back(table.names[std::size_t(j)]);
  }
  out.velocities = c.velocities;
  out.derivatives_given = !c.derivatives.empty();
  for (Eigen::Index j : c.derivatives) out.derivative_names.push_back(table.names[std::size_t(j)]);
  out.derivatives_by_name = out.derivatives_given && choice.derivatives.empty();
  if (c.time < 0) return scattered_states(std::move(table), c, std::move(out));
  out.time_name = table.names[std::size_t(c.time)];
  if (c.trajectory >= 0) out.trajectory_name = table.names[std::size_t(c.trajectory)];
  for (auto& [id, rows] : group_rows(table, c.trajectory)) {
    check_trajectory(table, c, id, rows);
    out.trajectory_ids.push_back(id);
    const auto pieces = cut_at_gaps(table, c.time, rows, choice.gap_factor);
    out.gaps += int(pieces.size()) - 1;
    for (const std::vector<Eigen::Index>& piece : pieces) {
      if (piece.size() < 3 && !out.derivatives_given) {
        out.dropped_rows += Eigen::Index(piece.size());  // too short to difference
        continue;
      }
      out.segments.push_back(make_segment(table, c, id, piece));
    }
  }
  HNN_TASKS_CHECK(!out.segments.empty(),
                  "{}: every stretch between gaps in time has fewer than 3 points, too few to "
                  "difference (raise the gap factor, or give derivative columns)",
                  table.source);
  out.table = std::move(table);
  return out;
}

}  // namespace hnn::tasks
