// A Hamiltonian system given by a formula over named coordinates and momenta, e.g.
// H = "p^2/2 + 9.81*(1 - cos(q))": parsed and differentiated exactly by GiNaC, then compiled
// once into straight-line code in double that evaluates H and the field on whole batches.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "physics/expression_program.h"
#include "physics/system.h"

namespace hnn::physics {

/// How an ExpressionSystem draws initial states: every variable uniform in its range
/// ([-1, 1] unless named here), and with an energy band only states whose H lies in it
/// (drawn from the box, the others rejected).
struct StateSampling {
  std::vector<std::pair<std::string, ValueRange>> ranges;
  std::optional<ValueRange> energy;
  long max_draws = 1'000'000;  ///< draws before giving up on filling the energy band
};

/// H(q, p) from an expression. Columns follow System: the coordinates in the order given,
/// then the momenta in theirs. The expression may use + - * / ^, parentheses, numbers,
/// Pi, and GiNaC's functions (sin, cos, tan, exp, log, sqrt, abs, atan2, sinh, ...).
///
/// Bad input throws std::invalid_argument naming what is wrong: an expression that does not
/// parse, an unknown name, coordinates and momenta of different counts, a duplicate name, a
/// name that is a function or constant (cos, Pi, ...), a function with no double evaluation.
/// hamiltonian_batch and vector_field throw std::invalid_argument naming the state when H or
/// the field is NaN or infinite there (log(q) at q <= 0, 1/q at 0).
class ExpressionSystem : public System {
 public:
  ExpressionSystem(std::string hamiltonian, std::vector<std::string> coords,
                   std::vector<std::string> momenta, StateSampling sampling = {});

  int dim() const override { return int(2 * coords_.size()); }
  /// "H = <the expression as given>".
  std::string name() const override;
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  void vector_field(const BatchView& x, Batch& dxdt) const override;
  /// As StateSampling says; deterministic in rng. Throws std::invalid_argument when the
  /// energy band stays unfilled after max_draws.
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;
  /// The exact halves when separable() (each half evaluates only its own derivatives).
  std::optional<SplitField> separable_split() const override;

  /// True when dH/dq does not depend on p and dH/dp not on q, decided symbolically on the
  /// expanded derivatives. An identity GiNaC does not simplify (sin(q+p)^2 + cos(q+p)^2)
  /// leaves it false: splitting methods then refuse a system they could have run.
  bool separable() const { return separable_; }
  const std::string& expression() const { return expression_; }
  const std::vector<std::string>& coords() const { return coords_; }
  const std::vector<std::string>& momenta() const { return momenta_; }
  /// Coordinates then momenta: the name of each column.
  std::vector<std::string> variables() const;
  /// dH/d(column j's variable), exact, as GiNaC prints it: "(9.81)*sin(q)" for d/dq above.
  const std::string& derivative_text(int column) const { return derivative_texts_.at(column); }
  /// The order-th derivatives of H at each row of x, differentiated symbolically and compiled
  /// for this call: R x dim^order, row r's entry d^order H / dx_i1 ... dx_ik at column
  /// i1 dim^(order-1) + ... + ik (each new index last). Order 0 is H. Throws
  /// std::invalid_argument for a negative order, or naming the state where one is not finite.
  Batch derivatives(const BatchView& x, int order) const;

  /// H and its symbols as GiNaC parsed them (defined in expression_system.cpp only).
  struct Parsed;

 private:
  void compile();
  void check_columns(const BatchView& x) const;
  // Throws naming the first state where an output of `program` is not finite.
  void check_finite(const BatchView& x, const Batch& out, const ExpressionProgram& program) const;
  Batch sample_box(int n, std::mt19937_64& rng) const;

  std::string expression_;
  std::vector<std::string> coords_, momenta_;
  std::vector<ValueRange> box_;  // the sampling range of each column
  std::optional<ValueRange> energy_band_;
  long max_draws_;
  bool separable_ = false;
  std::vector<std::string> derivative_texts_;
  ExpressionProgram h_, field_, drift_, kick_;
  // H and its symbols as parsed, which derivatives() differentiates: the same symbols each
  // call, so the same code and the same bits.
  std::shared_ptr<const Parsed> parsed_;
};

}  // namespace hnn::physics
