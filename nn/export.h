#pragma once
// A trained HNN's learned H taken anywhere: a self-contained C99 source file (H, its gradient
// and the field, weights embedded) or a JSON file of the weights with the formula.

#include <string>
#include <string_view>

#include "nn/dynamics.h"

namespace hnn::nn {

enum class ExportFormat { kC, kJson };

/// "c" or "json"; throws std::invalid_argument naming the known formats otherwise.
ExportFormat parse_export_format(std::string_view name);

/// Throws std::invalid_argument (one line) unless `model` is an exportable HNN: a solenoidal
/// HNN with tanh hidden layers and finite weights.
void check_exportable(const DynamicsModel<double>& model);

/// The exported file's text. `source` says where the model came from (one line, for the
/// header). The C file defines hnn_energy, hnn_gradient and hnn_field over
/// x = (q_1..q_n, p_1..p_n); weights are printed with 17 significant digits (exact).
std::string export_model(const DynamicsModel<double>& model, ExportFormat format,
                         std::string_view source);

}  // namespace hnn::nn
