// The split of measured trajectories into training and test data, and its description.
#include "tasks/data/measured_dataset.h"

#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "tasks/error.h"

namespace hnn::tasks {

namespace {

struct Parts {
  std::vector<Segment> train, test;
};

Segment slice(const Segment& s, Eigen::Index begin, Eigen::Index end) {
  const Eigen::Index n = end - begin;
  return {s.trajectory, std::vector<Eigen::Index>(s.rows.begin() + begin, s.rows.begin() + end),
          s.t.size() > 0 ? Eigen::VectorXd(s.t.segment(begin, n)) : Eigen::VectorXd(),  // scattered
          s.x.middleRows(begin, n), s.dxdt.middleRows(begin, n)};
}

// round(fraction * n), at least 1 and at most n - 1.
Eigen::Index test_count(double fraction, Eigen::Index n) {
  return std::clamp<Eigen::Index>(std::lround(fraction * double(n)), 1, n - 1);
}

Parts split_by_trajectories(const MeasuredTrajectories& m, double fraction) {
  const auto n = Eigen::Index(m.trajectory_ids.size());
  HNN_TASKS_CHECK(n >= 2,
                  "{}: a split by trajectories needs at least 2, and the file has 1 (split by "
                  "time instead)",
                  m.table.source);
  const std::set<double> test(m.trajectory_ids.end() - test_count(fraction, n),
                              m.trajectory_ids.end());
  Parts parts;
  for (const Segment& s : m.segments)
    (test.count(s.trajectory) ? parts.test : parts.train).push_back(s);
  return parts;
}

// The last rows of one trajectory's segments [first, last) go to the test set.
void split_one_by_time(const std::vector<Segment>& segments, std::size_t first, std::size_t last,
                       double fraction, Parts& parts) {
  Eigen::Index rows = 0;
  for (std::size_t k = first; k < last; ++k) rows += segments[k].t.size();
  const Eigen::Index cut = rows - test_count(fraction, rows);
  Eigen::Index offset = 0;
  for (std::size_t k = first; k < last; ++k) {
    const Segment& s = segments[k];
    const Eigen::Index size = s.t.size(), at = std::clamp<Eigen::Index>(cut - offset, 0, size);
    if (at > 0) parts.train.push_back(slice(s, 0, at));
    if (at < size) parts.test.push_back(slice(s, at, size));
    offset += size;
  }
}

Parts split_by_time(const MeasuredTrajectories& m, double fraction) {
  Parts parts;
  for (std::size_t first = 0, last = 0; first < m.segments.size(); first = last) {
    while (last < m.segments.size() &&
           m.segments[last].trajectory == m.segments[first].trajectory) {
      ++last;
    }
    split_one_by_time(m.segments, first, last, fraction, parts);
  }
  return parts;
}

Batch stack(const std::vector<Segment>& parts, Batch Segment::*member) {
  Eigen::Index rows = 0;
  for (const Segment& s : parts) rows += (s.*member).rows();
  Batch out(rows, parts.empty() ? 0 : (parts[0].*member).cols());
  rows = 0;
  for (const Segment& s : parts) {
    out.middleRows(rows, (s.*member).rows()) = s.*member;
    rows += (s.*member).rows();
  }
  return out;
}

int distinct_trajectories(const std::vector<Segment>& parts) {
  std::set<double> ids;
  for (const Segment& s : parts) ids.insert(s.trajectory);
  return int(ids.size());
}

// Scattered states: the file's last rows are the test set.
Parts split_by_rows(const MeasuredTrajectories& m, const SplitChoice& split) {
  HNN_TASKS_CHECK(split.by == SplitBy::kAuto,
                  "{}: split by {} needs trajectories, and the file holds scattered states (no "
                  "time column): leave the split at auto (the last rows are the test set)",
                  m.table.source, split.by == SplitBy::kTime ? "time" : "trajectories");
  const Segment& all = m.segments.at(0);
  const auto n = Eigen::Index(all.rows.size());
  HNN_TASKS_CHECK(n >= 2,
                  "{}: {} row{} of scattered states: at least 2 are needed (one to train, "
                  "one to test)",
                  m.table.source, n, n == 1 ? "" : "s");
  const Eigen::Index cut = n - test_count(split.test_fraction, n);
  return {{slice(all, 0, cut)}, {slice(all, cut, n)}};
}

}  // namespace

MeasuredData split_trajectories(const MeasuredTrajectories& m, const SplitChoice& split) {
  HNN_TASKS_CHECK(split.test_fraction > 0 && split.test_fraction < 1,
                  "test fraction {} is not between 0 and 1", split.test_fraction);
  MeasuredData out;
  out.scattered = m.scattered;
  out.split = split.by != SplitBy::kAuto    ? split.by
              : m.trajectory_ids.size() > 1 ? SplitBy::kTrajectories
                                            : SplitBy::kTime;
  const Parts parts = m.scattered ? split_by_rows(m, split)
                      : out.split == SplitBy::kTrajectories
                          ? split_by_trajectories(m, split.test_fraction)
                          : split_by_time(m, split.test_fraction);
  out.data = {stack(parts.train, &Segment::x), stack(parts.train, &Segment::dxdt),
              stack(parts.test, &Segment::x), stack(parts.test, &Segment::dxdt)};
  for (const Segment& s : parts.test) {
    if (s.t.size() >= 2) out.held_out.push_back({s.trajectory, m.table.where(s.rows[0]), s.t, s.x});
  }
  for (const Segment& s : parts.train) {
    if (s.t.size() >= 2)
      out.train_stretches.push_back({s.trajectory, m.table.where(s.rows[0]), s.t, s.x});
  }
  out.source = m.table.source;
  out.state_names = m.state_names;
  out.coordinates = m.coordinates;
  out.velocities = m.velocities;
  out.derivatives_given = m.derivatives_given;
  out.derivatives_by_name = m.derivatives_by_name;
  out.derivative_names = m.derivative_names;
  out.derivatives_note = m.derivatives_note;
  out.trajectories = int(m.trajectory_ids.size());
  out.test_trajectories = m.scattered ? 0 : distinct_trajectories(parts.test);
  out.gaps = m.gaps;
  out.dropped_rows = m.dropped_rows;
  return out;
}

MeasuredData load_measured_data(const std::string& path, const MeasuredDataOptions& options) {
  return split_trajectories(select_trajectories(read_table(path), options.columns), options.split);
}

std::string describe(const MeasuredData& d) {
  const auto names = [&](Eigen::Index from, Eigen::Index count) {
    return fmt::format(
        "{}", fmt::join(d.state_names.begin() + from, d.state_names.begin() + from + count, ", "));
  };
  std::string text = fmt::format(
      "{}: {}; coordinates {}; {} {}{}\n", d.source,
      d.scattered
          ? "scattered states (no time column)"
          : fmt::format("{} trajector{}", d.trajectories, d.trajectories == 1 ? "y" : "ies"),
      names(0, d.coordinates), d.velocities ? "velocities" : "momenta",
      names(d.coordinates, d.coordinates),
      d.velocities ? " (velocities taken as momenta: unit masses assumed)" : "");
  if (d.scattered) {
    return text + fmt::format(
                      "dx/dt from the file's derivative columns ({})\nsplit by rows: {} "
                      "training rows, {} test rows (the file's last)",
                      fmt::join(d.derivative_names, ", "), d.data.train_x.rows(),
                      d.data.test_x.rows());
  }
  text += d.derivatives_given ? "dx/dt from the file's derivative columns"
                              : "dx/dt by finite differences within each trajectory";
  if (d.derivatives_by_name)
    text += fmt::format(" ({}, found by name)", fmt::join(d.derivative_names, ", "));
  if (d.gaps > 0) text += fmt::format(", cut at {} gap{} in time", d.gaps, d.gaps == 1 ? "" : "s");
  if (d.dropped_rows > 0) {
    text += fmt::format(" ({} rows between gaps, in stretches under 3 points, left out)",
                        d.dropped_rows);
  }
  text +=
      fmt::format("\nsplit by {}: {} training rows, {} test rows ({} of the {} trajectories)",
                  d.split == SplitBy::kTrajectories ? "trajectories" : "time",
                  d.data.train_x.rows(), d.data.test_x.rows(), d.test_trajectories, d.trajectories);
  return text;
}

std::string derivatives_source(const MeasuredData& d) {
  if (d.derivatives_by_name) {
    return fmt::format(
        "{}: dx/dt from the columns {}, found by name (--derivatives names others; "
        "--derivatives none takes finite differences)",
        d.source, fmt::join(d.derivative_names, ", "));
  }
  if (d.derivatives_given)
    return fmt::format("{}: dx/dt from the columns {}", d.source,
                       fmt::join(d.derivative_names, ", "));
  return fmt::format(
      "{}: dx/dt by finite differences within each trajectory ({})", d.source,
      d.derivatives_note.empty()
          ? "no derivative columns such as d" + d.state_names[0] + "/dt: --derivatives names them"
          : d.derivatives_note);
}

}  // namespace hnn::tasks
