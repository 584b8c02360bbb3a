// ExpressionProgram: appending instructions and running them block by block.
#include "physics/expression_program.h"

#include <cassert>
#include <cmath>

namespace hnn::physics {
namespace {

// Rows evaluated together: long enough for vectorised loops, short enough that every register
// of a block (rows x instructions doubles) stays in cache.
constexpr Eigen::Index kBlockRows = 128;

using Op = Instruction::Op;

// One instruction over a block; r(k) is register k's column.
template <typename Registers>
void execute(const Instruction& in, const BatchView& x, Eigen::Index row0, Registers&& r, int out) {
  auto y = r.col(out);
  const Eigen::Index m = y.rows();
  switch (in.op) {
    case Op::kConst:
      y.setConstant(in.value);
      return;
    case Op::kVariable:
      y = x.col(Eigen::Index(in.value)).segment(row0, m).array();
      return;
    case Op::kAdd:
      y = r.col(in.a) + r.col(in.b);
      return;
    case Op::kSub:
      y = r.col(in.a) - r.col(in.b);
      return;
    case Op::kMul:
      y = r.col(in.a) * r.col(in.b);
      return;
    case Op::kDiv:
      y = r.col(in.a) / r.col(in.b);
      return;
    case Op::kScale:
      y = in.value * r.col(in.a);
      return;
    case Op::kOffset:
      y = r.col(in.a) + in.value;
      return;
    case Op::kNeg:
      y = -r.col(in.a);
      return;
    case Op::kSquare:
      y = r.col(in.a).square();
      return;
    case Op::kInverse:
      y = r.col(in.a).inverse();
      return;
    case Op::kSqrt:
      y = r.col(in.a).sqrt();
      return;
    case Op::kPowConst:
      y = r.col(in.a).pow(in.value);
      return;
    case Op::kPow:
      y = r.col(in.a).pow(r.col(in.b));
      return;
    case Op::kAtan2:
      y = r.col(in.a).binaryExpr(r.col(in.b), [](double u, double v) { return std::atan2(u, v); });
      return;
    case Op::kSin:
      y = r.col(in.a).sin();
      return;
    case Op::kCos:
      y = r.col(in.a).cos();
      return;
    case Op::kTan:
      y = r.col(in.a).tan();
      return;
    case Op::kAsin:
      y = r.col(in.a).asin();
      return;
    case Op::kAcos:
      y = r.col(in.a).acos();
      return;
    case Op::kAtan:
      y = r.col(in.a).atan();
      return;
    case Op::kSinh:
      y = r.col(in.a).sinh();
      return;
    case Op::kCosh:
      y = r.col(in.a).cosh();
      return;
    case Op::kTanh:
      y = r.col(in.a).tanh();
      return;
    case Op::kAsinh:
      y = r.col(in.a).unaryExpr([](double u) { return std::asinh(u); });
      return;
    case Op::kAcosh:
      y = r.col(in.a).unaryExpr([](double u) { return std::acosh(u); });
      return;
    case Op::kAtanh:
      y = r.col(in.a).unaryExpr([](double u) { return std::atanh(u); });
      return;
    case Op::kExp:
      y = r.col(in.a).exp();
      return;
    case Op::kLog:
      y = r.col(in.a).log();
      return;
    case Op::kAbs:
      y = r.col(in.a).abs();
      return;
    case Op::kSign:
      y = r.col(in.a).sign();
      return;
  }
}

}  // namespace

int ExpressionProgram::add(const Instruction& instruction) {
  assert(instruction.a < size() && instruction.b < size());
  code_.push_back(instruction);
  return size() - 1;
}

void ExpressionProgram::add_output(int reg, std::string name) {
  assert(reg >= 0 && reg < size());
  outputs_.push_back(reg);
  output_names_.push_back(std::move(name));
}

void ExpressionProgram::run_block(const BatchView& x, Eigen::Index row0,
                                  Eigen::ArrayXXd& reg) const {
  for (int i = 0; i < size(); ++i) execute(code_[i], x, row0, reg, i);
}

void ExpressionProgram::evaluate(const BatchView& x, Batch& out) const {
  out.resize(x.rows(), outputs());
  Eigen::ArrayXXd reg(std::min(kBlockRows, x.rows()), size());
  for (Eigen::Index row0 = 0; row0 < x.rows(); row0 += kBlockRows) {
    const Eigen::Index m = std::min(kBlockRows, x.rows() - row0);
    if (m != reg.rows()) reg.resize(m, size());
    run_block(x, row0, reg);
    for (int k = 0; k < outputs(); ++k) out.col(k).segment(row0, m) = reg.col(outputs_[k]);
  }
}

}  // namespace hnn::physics
