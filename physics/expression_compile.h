// Internal to physics (expression_system.cpp): GiNaC expressions compiled into one
// ExpressionProgram, with every subexpression they share computed once.
#pragma once

#include <ginac/ginac.h>

#include <map>
#include <string>
#include <vector>

#include "physics/expression_program.h"

namespace hnn::physics::detail {

/// The state column of each symbol.
using ColumnOf = std::map<GiNaC::ex, int, GiNaC::ex_is_less>;

struct NamedExpression {
  std::string name;
  GiNaC::ex value;
};

/// One program whose outputs are `outputs`, in order. Throws std::invalid_argument naming a
/// part with no evaluation in double (a complex number, an unsupported function, a symbolic
/// derivative such as D[0](csgn)(q)); `where` starts the message.
ExpressionProgram compile_expressions(const std::vector<NamedExpression>& outputs,
                                      const ColumnOf& columns, const std::string& where);

}  // namespace hnn::physics::detail
