// A small straight-line program in double that evaluates several expressions over the same
// variables on a batch of states: what a symbolic H and its derivatives compile into.
#pragma once

#include <string>
#include <vector>

#include "physics/types.h"

namespace hnn::physics {

/// One instruction. Instruction i writes register i (each register is written once), reading
/// the registers a and b of earlier instructions; `value` is a constant, a column index or an
/// exponent, as the op says.
struct Instruction {
  enum class Op {
    kConst,     ///< value
    kVariable,  ///< column `value` of the state
    kAdd,       ///< a + b
    kSub,       ///< a - b
    kMul,       ///< a * b
    kDiv,       ///< a / b
    kScale,     ///< value * a
    kOffset,    ///< a + value
    kNeg,       ///< -a
    kSquare,    ///< a * a
    kInverse,   ///< 1 / a
    kSqrt,
    kPowConst,  ///< a ^ value
    kPow,       ///< a ^ b
    kAtan2,     ///< atan2(a, b)
    kSin,
    kCos,
    kTan,
    kAsin,
    kAcos,
    kAtan,
    kSinh,
    kCosh,
    kTanh,
    kAsinh,
    kAcosh,
    kAtanh,
    kExp,
    kLog,
    kAbs,
    kSign,  ///< -1, 0 or 1 (GiNaC's csgn on reals)
  };
  Op op = Op::kConst;
  int a = -1;
  int b = -1;
  double value = 0.0;
};

/// Straight-line code with named outputs. Built once (by the expression compiler), then
/// evaluated on blocks of rows so that every instruction is one vectorised loop.
class ExpressionProgram {
 public:
  /// Appends an instruction and returns its register.
  int add(const Instruction& instruction);
  /// Marks register `reg` as an output called `name` (outputs keep this order).
  void add_output(int reg, std::string name);

  int size() const { return int(code_.size()); }
  int outputs() const { return int(outputs_.size()); }
  const std::string& output_name(int k) const { return output_names_[k]; }

  /// out(i, k) = output k at state row i; out is resized to x.rows() x outputs(). Values may be
  /// non-finite: the caller checks (it knows what the outputs mean).
  void evaluate(const BatchView& x, Batch& out) const;

 private:
  void run_block(const BatchView& x, Eigen::Index row0, Eigen::ArrayXXd& reg) const;

  std::vector<Instruction> code_;
  std::vector<int> outputs_;
  std::vector<std::string> output_names_;
};

}  // namespace hnn::physics
