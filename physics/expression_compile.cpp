// GiNaC expression trees to straight-line code: sums, products and quotients, integer powers
// by repeated squaring, the elementary functions; shared subexpressions once.
#include "physics/expression_compile.h"

#include <fmt/format.h>

#include <sstream>
#include <stdexcept>

namespace hnn::physics::detail {
namespace {

using Op = Instruction::Op;

std::string text_of(const GiNaC::ex& e) {
  std::ostringstream out;
  out << e;
  return out.str();
}

const std::map<std::string, Op>& unary_functions() {
  static const std::map<std::string, Op> table = {
      {"sin", Op::kSin},   {"cos", Op::kCos},     {"tan", Op::kTan},     {"asin", Op::kAsin},
      {"acos", Op::kAcos}, {"atan", Op::kAtan},   {"sinh", Op::kSinh},   {"cosh", Op::kCosh},
      {"tanh", Op::kTanh}, {"asinh", Op::kAsinh}, {"acosh", Op::kAcosh}, {"atanh", Op::kAtanh},
      {"exp", Op::kExp},   {"log", Op::kLog},     {"abs", Op::kAbs},     {"csgn", Op::kSign}};
  return table;
}

class Compiler {
 public:
  Compiler(const ColumnOf& columns, std::string where)
      : columns_(columns), where_(std::move(where)) {}

  int emit(const GiNaC::ex& e) {
    const auto seen = memo_.find(e);
    if (seen != memo_.end()) return seen->second;
    const int reg = emit_new(e);
    memo_.emplace(e, reg);
    return reg;
  }

  ExpressionProgram take() { return std::move(program_); }

 private:
  int op(Op o, int a = -1, int b = -1, double value = 0.0) {
    return program_.add({.op = o, .a = a, .b = b, .value = value});
  }

  [[noreturn]] void unsupported(const GiNaC::ex& e, const std::string& why) const {
    throw std::invalid_argument(
        fmt::format("{}: cannot evaluate '{}' in double: {}", where_, text_of(e), why));
  }

  double real_value(const GiNaC::ex& e) const {
    const GiNaC::numeric n = GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(e));
    if (!n.is_real()) unsupported(e, "H must be real (is I in it?)");
    return n.to_double();
  }

  int emit_new(const GiNaC::ex& e) {
    if (GiNaC::is_a<GiNaC::numeric>(e) || GiNaC::is_a<GiNaC::constant>(e)) {
      return op(Op::kConst, -1, -1, real_value(e));
    }
    if (GiNaC::is_a<GiNaC::symbol>(e)) {
      const auto column = columns_.find(e);
      if (column == columns_.end()) unsupported(e, "not a coordinate or momentum");
      return op(Op::kVariable, -1, -1, column->second);
    }
    if (GiNaC::is_a<GiNaC::add>(e)) return emit_sum(e);
    if (GiNaC::is_a<GiNaC::mul>(e)) return emit_product(e);
    if (GiNaC::is_a<GiNaC::power>(e)) return emit_power(e);
    // A derivative GiNaC could not write out is also a function: test it first.
    if (GiNaC::is_a<GiNaC::fderivative>(e)) unsupported(e, "no closed-form derivative");
    if (GiNaC::is_a<GiNaC::function>(e)) return emit_function(e);
    unsupported(e, "not an arithmetic expression");
  }

  // The numeric factor of a term (3 in 3*x*y), 1 if it has none.
  double coefficient(const GiNaC::ex& term) const {
    double c = 1.0;
    if (!GiNaC::is_a<GiNaC::mul>(term)) return c;
    for (const GiNaC::ex& f : term) {
      if (GiNaC::is_a<GiNaC::numeric>(f)) c *= real_value(f);
    }
    return c;
  }

  // Terms with a negative factor become subtractions of their negation (a - 2b, not a + -2b).
  int emit_sum(const GiNaC::ex& e) {
    double offset = 0.0;
    int sum = -1;
    for (const GiNaC::ex& term : e) {
      if (GiNaC::is_a<GiNaC::numeric>(term) || GiNaC::is_a<GiNaC::constant>(term)) {
        offset += real_value(term);
        continue;
      }
      const bool negative = coefficient(term) < 0.0;
      const int r = emit(negative ? GiNaC::ex(-term) : term);
      if (sum < 0) {
        sum = negative ? op(Op::kNeg, r) : r;
      } else {
        sum = op(negative ? Op::kSub : Op::kAdd, sum, r);
      }
    }
    if (sum < 0) return op(Op::kConst, -1, -1, offset);
    return offset == 0.0 ? sum : op(Op::kOffset, sum, -1, offset);
  }

  int multiply(int acc, int r) { return acc < 0 ? r : op(Op::kMul, acc, r); }

  // coefficient * (factors with positive powers) / (factors with negative powers).
  int emit_product(const GiNaC::ex& e) {
    double scale = 1.0;
    int numerator = -1, denominator = -1;
    for (const GiNaC::ex& f : e) {
      if (GiNaC::is_a<GiNaC::numeric>(f) || GiNaC::is_a<GiNaC::constant>(f)) {
        scale *= real_value(f);
      } else if (GiNaC::is_a<GiNaC::power>(f) && GiNaC::is_a<GiNaC::numeric>(f.op(1)) &&
                 GiNaC::ex_to<GiNaC::numeric>(f.op(1)).is_negative()) {
        denominator = multiply(denominator, emit(GiNaC::pow(f.op(0), -f.op(1))));
      } else {
        numerator = multiply(numerator, emit(f));
      }
    }
    if (numerator < 0) {
      const int c = op(Op::kConst, -1, -1, scale);
      return denominator < 0 ? c : op(Op::kDiv, c, denominator);
    }
    int r = denominator < 0 ? numerator : op(Op::kDiv, numerator, denominator);
    if (scale == -1.0) return op(Op::kNeg, r);
    return scale == 1.0 ? r : op(Op::kScale, r, -1, scale);
  }

  int integer_power(int base, long n) {
    if (n < 0) return op(Op::kInverse, integer_power(base, -n));
    if (n == 0) return op(Op::kConst, -1, -1, 1.0);
    int result = -1, square = base;  // square = base^(2^k) at bit k
    while (true) {
      if (n & 1) result = multiply(result, square);
      n >>= 1;
      if (n == 0) return result;
      square = op(Op::kSquare, square);
    }
  }

  int emit_power(const GiNaC::ex& e) {
    const int base = emit(e.op(0));
    if (!GiNaC::is_a<GiNaC::numeric>(e.op(1))) return op(Op::kPow, base, emit(e.op(1)));
    const GiNaC::numeric exponent = GiNaC::ex_to<GiNaC::numeric>(e.op(1));
    if (exponent.is_integer() && abs(exponent) < 64) return integer_power(base, exponent.to_long());
    const double v = real_value(exponent);
    if (v == 0.5) return op(Op::kSqrt, base);
    if (v == -0.5) return op(Op::kInverse, op(Op::kSqrt, base));
    return op(Op::kPowConst, base, -1, v);
  }

  int emit_function(const GiNaC::ex& e) {
    const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
    if (name == "atan2") return op(Op::kAtan2, emit(e.op(0)), emit(e.op(1)));
    const auto unary = unary_functions().find(name);
    if (unary == unary_functions().end() || e.nops() != 1) {
      unsupported(e, fmt::format("the function '{}' is not supported", name));
    }
    return op(unary->second, emit(e.op(0)));
  }

  const ColumnOf& columns_;
  std::string where_;
  ExpressionProgram program_;
  std::map<GiNaC::ex, int, GiNaC::ex_is_less> memo_;
};

}  // namespace

ExpressionProgram compile_expressions(const std::vector<NamedExpression>& outputs,
                                      const ColumnOf& columns, const std::string& where) {
  Compiler compiler(columns, where);
  std::vector<int> regs;
  for (const NamedExpression& out : outputs) regs.push_back(compiler.emit(out.value));
  ExpressionProgram program = compiler.take();
  for (std::size_t k = 0; k < outputs.size(); ++k) program.add_output(regs[k], outputs[k].name);
  return program;
}

}  // namespace hnn::physics::detail
