// ExpressionSystem: names checked, the expression parsed and differentiated by GiNaC, H, the
// field and its two halves compiled once; sampling from a box or an energy band.
#include "physics/expression_system.h"

#include <fmt/format.h>
#include <ginac/ginac.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>

#include "physics/expression_compile.h"

namespace hnn::physics {
namespace {

std::string joined(const std::vector<std::string>& names) {
  return names.empty() ? "none" : fmt::format("{}", fmt::join(names, ", "));
}

// Names the parser reads as something else: its functions (cos, exp, ...) and constants.
const std::set<std::string>& reserved_names() {
  static const std::set<std::string> names = [] {
    std::set<std::string> s = {"I", "Pi", "Euler", "Catalan"};
    for (const auto& entry : GiNaC::get_default_reader()) s.insert(entry.first.first);
    return s;
  }();
  return names;
}

bool is_identifier(const std::string& name) {
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0]))) return false;
  for (char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  }
  return true;
}

void check_names(const std::vector<std::string>& coords, const std::vector<std::string>& momenta) {
  if (coords.empty() || coords.size() != momenta.size()) {
    throw std::invalid_argument(
        fmt::format("hamiltonian: {} coordinates ({}) and {} momenta ({}): give one momentum per "
                    "coordinate, at least one of each",
                    coords.size(), joined(coords), momenta.size(), joined(momenta)));
  }
  std::set<std::string> seen;
  for (std::size_t j = 0; j < 2 * coords.size(); ++j) {
    const bool coordinate = j < coords.size();
    const std::string& name = coordinate ? coords[j] : momenta[j - coords.size()];
    const char* kind = coordinate ? "coordinate" : "momentum";
    if (!is_identifier(name)) {
      throw std::invalid_argument(fmt::format(
          "hamiltonian: {} name '{}' is not a name (letters, digits and _, not starting with a "
          "digit)",
          kind, name));
    }
    if (reserved_names().count(name) > 0) {
      throw std::invalid_argument(fmt::format(
          "hamiltonian: {} name '{}' is a function or constant of the expression language; "
          "choose another",
          kind, name));
    }
    if (!seen.insert(name).second) {
      throw std::invalid_argument(
          fmt::format("hamiltonian: the name '{}' is given twice (coordinates {}; momenta {})",
                      name, joined(coords), joined(momenta)));
    }
  }
}

// GiNaC's message without its source location: "unexpected token, got: EOF".
std::string parse_reason(const std::string& what) {
  std::string reason = what.substr(0, what.find('\n'));
  const std::size_t colon = reason.rfind("column 0: ");
  if (colon != std::string::npos) reason = reason.substr(colon + 10);
  return reason;
}

GiNaC::ex parse_hamiltonian(const std::string& text, const std::vector<GiNaC::ex>& symbols,
                            const std::vector<std::string>& names, std::size_t coords) {
  GiNaC::symtab table;
  for (std::size_t j = 0; j < names.size(); ++j) table[names[j]] = symbols[j];
  GiNaC::parser reader(table, /*strict=*/false);  // unknown names are collected, then reported
  GiNaC::ex h;
  try {
    h = reader(text);
  } catch (const std::exception& e) {
    // Python's power operator is the commonest slip: GiNaC reads only ^.
    const char* hint =
        text.find("**") != std::string::npos ? " (write powers with ^: q^4, not q**4)" : "";
    throw std::invalid_argument(
        fmt::format("hamiltonian '{}' does not parse: {}{}", text, parse_reason(e.what()), hint));
  }
  std::vector<std::string> unknown;
  for (const auto& [name, value] : reader.get_syms()) {
    if (table.count(name) == 0) unknown.push_back("'" + name + "'");
  }
  if (!unknown.empty()) {
    const std::vector<std::string> q(names.begin(), names.begin() + long(coords));
    const std::vector<std::string> p(names.begin() + long(coords), names.end());
    throw std::invalid_argument(
        fmt::format("hamiltonian '{}': unknown name {} (coordinates: {}; momenta: {})", text,
                    fmt::join(unknown, ", "), joined(q), joined(p)));
  }
  return h;
}

bool depends_on_any(const GiNaC::ex& e, const std::vector<GiNaC::ex>& symbols) {
  const GiNaC::ex expanded = GiNaC::expand(e);
  for (const GiNaC::ex& s : symbols) {
    if (expanded.has(s)) return true;
  }
  return false;
}

// "NaN" rather than the platform's "-nan".
std::string value_text(double v) { return std::isnan(v) ? "NaN" : fmt::format("{}", v); }

std::string text_of(const GiNaC::ex& e) {
  std::ostringstream out;
  out << e;
  return out.str();
}

}  // namespace

// H parsed over one symbol per column.
struct ExpressionSystem::Parsed {
  std::vector<GiNaC::ex> symbols;
  detail::ColumnOf column_of;
  GiNaC::ex h;
};

namespace {

using Parsed = ExpressionSystem::Parsed;

Parsed parse(const std::string& expression, const std::vector<std::string>& names,
             std::size_t coords) {
  Parsed parsed;
  for (const std::string& name : names) {
    parsed.symbols.push_back(GiNaC::realsymbol(name));  // real: |q|' and conjugates simplify
    parsed.column_of[parsed.symbols.back()] = int(parsed.symbols.size()) - 1;
  }
  parsed.h = parse_hamiltonian(expression, parsed.symbols, names, coords);
  return parsed;
}

// d^k h / dx_i1 ... dx_ik for `sorted` = (i1 <= ... <= ik), each computed once in `memo`.
const GiNaC::ex& partial(const Parsed& parsed, const std::vector<int>& sorted,
                         std::map<std::vector<int>, GiNaC::ex>& memo) {
  if (const auto seen = memo.find(sorted); seen != memo.end()) return seen->second;
  const std::vector<int> rest(sorted.begin(), sorted.end() - 1);
  const GiNaC::ex d =
      partial(parsed, rest, memo).diff(GiNaC::ex_to<GiNaC::symbol>(parsed.symbols[sorted.back()]));
  return memo.emplace(sorted, d).first->second;
}

}  // namespace

ExpressionSystem::ExpressionSystem(std::string hamiltonian, std::vector<std::string> coords,
                                   std::vector<std::string> momenta, StateSampling sampling)
    : expression_(std::move(hamiltonian)),
      coords_(std::move(coords)),
      momenta_(std::move(momenta)),
      energy_band_(sampling.energy),
      max_draws_(sampling.max_draws) {
  check_names(coords_, momenta_);
  const std::vector<std::string> names = variables();
  box_.assign(names.size(), ValueRange{});
  for (const auto& [name, range] : sampling.ranges) {
    const auto at = std::find(names.begin(), names.end(), name);
    if (at == names.end()) {
      throw std::invalid_argument(
          fmt::format("sampling range for '{}', which is not a coordinate or momentum ({})", name,
                      joined(names)));
    }
    if (!(range.lo < range.hi) || !std::isfinite(range.lo) || !std::isfinite(range.hi)) {
      throw std::invalid_argument(fmt::format(
          "sampling range of '{}' is {}:{}; it needs finite lo < hi", name, range.lo, range.hi));
    }
    box_[at - names.begin()] = range;
  }
  if (energy_band_ && (!(energy_band_->lo <= energy_band_->hi) ||
                       !std::isfinite(energy_band_->lo) || !std::isfinite(energy_band_->hi))) {
    throw std::invalid_argument(
        fmt::format("energy band {}:{} needs finite LO <= HI", energy_band_->lo, energy_band_->hi));
  }
  compile();
}

void ExpressionSystem::compile() {
  const std::vector<std::string> names = variables();
  const std::size_t n = coords_.size();
  parsed_ = std::make_shared<const Parsed>(parse(expression_, names, n));
  const auto& [symbols, column_of, h] = *parsed_;
  const std::vector<GiNaC::ex> q(symbols.begin(), symbols.begin() + long(n));
  const std::vector<GiNaC::ex> p(symbols.begin() + long(n), symbols.end());
  std::vector<detail::NamedExpression> drift, kick;
  separable_ = true;
  for (std::size_t i = 0; i < n; ++i) {
    const GiNaC::ex dh_dp = h.diff(GiNaC::ex_to<GiNaC::symbol>(p[i]));
    const GiNaC::ex dh_dq = h.diff(GiNaC::ex_to<GiNaC::symbol>(q[i]));
    separable_ = separable_ && !depends_on_any(dh_dp, q) && !depends_on_any(dh_dq, p);
    drift.push_back({"dH/d" + momenta_[i], dh_dp});
    kick.push_back({"-dH/d" + coords_[i], -dh_dq});
  }
  derivative_texts_.resize(2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    derivative_texts_[i] = text_of(-kick[i].value);
    derivative_texts_[n + i] = text_of(drift[i].value);
  }
  const std::string where = name();
  h_ = detail::compile_expressions({{"H", h}}, column_of, where);
  drift_ = detail::compile_expressions(drift, column_of, where);
  kick_ = detail::compile_expressions(kick, column_of, where);
  std::vector<detail::NamedExpression> field = drift;
  field.insert(field.end(), kick.begin(), kick.end());
  field_ = detail::compile_expressions(field, column_of, where);
}

std::string ExpressionSystem::name() const { return "H = " + expression_; }

std::vector<std::string> ExpressionSystem::variables() const {
  std::vector<std::string> names = coords_;
  names.insert(names.end(), momenta_.begin(), momenta_.end());
  return names;
}

void ExpressionSystem::check_columns(const BatchView& x) const {
  if (x.cols() != dim()) {
    throw std::invalid_argument(fmt::format("{}: state has {} columns, expected {} ({})", name(),
                                            x.cols(), dim(), joined(variables())));
  }
}

void ExpressionSystem::check_finite(const BatchView& x, const Batch& out,
                                    const ExpressionProgram& program) const {
  if (out.allFinite()) return;
  Eigen::Index row = 0, k = 0;
  while (std::isfinite(out(row, k))) {
    if (++k == out.cols()) k = 0, ++row;
  }
  const std::vector<std::string> names = variables();
  std::vector<std::string> state;
  for (Eigen::Index j = 0; j < x.cols(); ++j)
    state.push_back(fmt::format("{} = {}", names[j], x(row, j)));
  throw std::invalid_argument(fmt::format("{}: {} is {} at state {} ({})", name(),
                                          program.output_name(int(k)), value_text(out(row, k)), row,
                                          fmt::join(state, ", ")));
}

Eigen::VectorXd ExpressionSystem::hamiltonian_batch(const BatchView& x) const {
  check_columns(x);
  Batch h;
  h_.evaluate(x, h);
  check_finite(x, h, h_);
  return h.col(0);
}

void ExpressionSystem::vector_field(const BatchView& x, Batch& dxdt) const {
  check_columns(x);
  field_.evaluate(x, dxdt);
  check_finite(x, dxdt, field_);
}

Batch ExpressionSystem::derivatives(const BatchView& x, int order) const {
  check_columns(x);
  if (order < 0)
    throw std::invalid_argument(
        fmt::format("{}: derivative of order {} (0 or more)", name(), order));
  const std::vector<std::string> names = variables();
  const Parsed& parsed = *parsed_;
  // GiNaC's expressions share reference counts without locks: one call at a time touches them
  // (the evaluation below runs in parallel).
  static std::mutex ginac;
  std::unique_lock<std::mutex> lock(ginac);
  std::map<std::vector<int>, GiNaC::ex> memo{{{}, parsed.h}};  // mixed partials commute
  std::vector<detail::NamedExpression> outputs;
  long entries = 1;
  for (int k = 0; k < order; ++k) entries *= dim();
  for (long entry = 0; entry < entries; ++entry) {
    std::vector<int> index(static_cast<std::size_t>(order));  // i1..ik, ik running fastest
    long rest = entry;
    for (auto i = index.rbegin(); i != index.rend(); ++i, rest /= dim()) *i = int(rest % dim());
    std::string what = order == 0 ? "H" : fmt::format("d^{} H /", order);
    for (int i : index) what += " d" + names[std::size_t(i)];
    std::sort(index.begin(), index.end());
    outputs.push_back({std::move(what), partial(parsed, index, memo)});
  }
  const ExpressionProgram program = detail::compile_expressions(outputs, parsed.column_of, name());
  memo.clear();
  outputs.clear();
  lock.unlock();
  Batch out;
  program.evaluate(x, out);
  check_finite(x, out, program);
  return out;
}

std::optional<SplitField> ExpressionSystem::separable_split() const {
  if (!separable_) return std::nullopt;
  // Each half reads only its own block, but the programs index whole-state columns.
  return SplitField{[this](double, const Batch& x, Batch& dq) {
                      check_columns(x);
                      drift_.evaluate(x, dq);
                      check_finite(x, dq, drift_);
                    },
                    [this](double, const Batch& x, Batch& dp) {
                      check_columns(x);
                      kick_.evaluate(x, dp);
                      check_finite(x, dp, kick_);
                    }};
}

Batch ExpressionSystem::sample_box(int n, std::mt19937_64& rng) const {
  return physics::sample_box(n, box_, rng);
}

Batch ExpressionSystem::sample_initial_states(int n, std::mt19937_64& rng) const {
  if (n < 0) throw std::invalid_argument(fmt::format("{}: cannot sample {} states", name(), n));
  if (!energy_band_) return sample_box(n, rng);
  constexpr int kDrawsPerRound = 1024;
  Batch accepted(n, dim());
  Eigen::Index filled = 0;
  Batch h;
  for (long draws = 0; filled < n; draws += kDrawsPerRound) {
    if (draws >= max_draws_) {
      throw std::invalid_argument(fmt::format(
          "{}: only {} of {} states with H in [{}, {}] after {} draws from the sampling box; "
          "widen the ranges or the band",
          name(), filled, n, energy_band_->lo, energy_band_->hi, draws));
    }
    const Batch x = sample_box(kDrawsPerRound, rng);
    h_.evaluate(x, h);  // a NaN H is simply never in the band
    for (Eigen::Index i = 0; i < x.rows() && filled < n; ++i) {
      if (h(i, 0) >= energy_band_->lo && h(i, 0) <= energy_band_->hi) {
        accepted.row(filled++) = x.row(i);
      }
    }
  }
  return accepted;
}

}  // namespace hnn::physics
