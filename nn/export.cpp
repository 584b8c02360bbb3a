#include "nn/export.h"

#include <fmt/format.h>

#include <algorithm>
#include <optional>
#include <stdexcept>

#include "nn/enum_names.h"
#include "nn/hnn.h"

namespace hnn::nn {

namespace {

constexpr NameTable<ExportFormat, 2> kExportFormatNames{{
    {ExportFormat::kC, "c"},
    {ExportFormat::kJson, "json"},
}};

std::string number(double v) { return fmt::format("{:.17g}", v); }

const char* const kFormula =
    "h_0 = x = (q_1..q_n, p_1..p_n); h_l = tanh(h_{l-1} W_l + b_l) for each hidden layer; "
    "H(x) = h_L W_out (+ b_out); dx/dt = (dH/dp, -dH/dq)";

bool all_finite(const Matrix<double>& m) { return m.allFinite(); }

/// The values of a matrix row by row, comma-separated.
std::string flat_values(const Matrix<double>& m) {
  std::string out;
  for (Index i = 0; i < m.rows(); ++i) {
    for (Index j = 0; j < m.cols(); ++j) {
      if (!out.empty()) out += ", ";
      out += number(m(i, j));
    }
  }
  return out;
}

/// `source` without what would end a C comment or break a JSON string.
std::string clean_source(std::string_view source) {
  std::string out;
  for (char c : source) {
    if (c == '"' || c == '\\' || static_cast<unsigned char>(c) < 0x20) continue;
    if (c == '/' && !out.empty() && out.back() == '*') out += ' ';
    out += c;
  }
  return out;
}

// ---- C ----------------------------------------------------------------------------------

std::string c_header(const DynamicsModel<double>& model, std::string_view source) {
  return fmt::format(
      "/* Exported by `hnn export` from {}: {}.\n"
      " * {}.\n"
      " * Self-contained C99 (only <math.h>): hnn_energy(x) = H(x), hnn_gradient(x, g) = dH/dx,\n"
      " * hnn_field(x, dxdt) = (dH/dp, -dH/dq); x has {} entries (q then p). Weights are\n"
      " * in x out, row by row, with 17 significant digits (exact in double). */\n"
      "#include <math.h>\n\n",
      clean_source(source), model.describe(), kFormula, model.dim());
}

std::string c_tables(const Mlp<double>& mlp) {
  const auto& layers = mlp.layers();
  const std::size_t hidden = layers.size() - 1;
  std::string widths, offsets, weights, biases, out;
  Index total = 0, widest = mlp.input_dim();
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const Linear<double>& layer = layers[l];
    widths += fmt::format("{}, ", layer.in_features());
    widest = std::max(widest, layer.out_features());
    out += fmt::format("static const double hnn_w{}[{}] = {{{}}};\n", l,
                       layer.in_features() * layer.out_features(),
                       flat_values(layer.weight().value()));
    weights += fmt::format("hnn_w{}, ", l);
    if (layer.has_bias()) {
      out += fmt::format("static const double hnn_b{}[{}] = {{{}}};\n", l, layer.out_features(),
                         flat_values(layer.bias().value()));
      biases += fmt::format("hnn_b{}, ", l);
    } else {
      biases += "0, ";
    }
    if (l < hidden) {
      offsets += fmt::format("{}, ", total);
      total += layer.out_features();
    }
  }
  offsets += fmt::format("{}", total);
  widths += "1";
  return fmt::format(
      "#define HNN_DIM {}\n#define HNN_HIDDEN {}\n#define HNN_ACTS {}\n#define HNN_WIDEST {}\n"
      "static const int hnn_width[HNN_HIDDEN + 2] = {{{}}};\n"
      "static const int hnn_offset[HNN_HIDDEN + 1] = {{{}}};\n{}"
      "static const double* const hnn_weight[HNN_HIDDEN + 1] = {{{}}};\n"
      "static const double* const hnn_bias[HNN_HIDDEN + 1] = {{{}}};\n\n",
      mlp.input_dim(), hidden, std::max<Index>(total, 1), widest, widths, offsets, out,
      weights.substr(0, weights.size() - 2), biases.substr(0, biases.size() - 2));
}

const char* const kCFunctions = R"(/* out = in W_l + b_l. */
static void hnn_affine(const double* in, int l, double* out) {
  const int rows = hnn_width[l], cols = hnn_width[l + 1];
  const double* w = hnn_weight[l];
  int i, j;
  for (j = 0; j < cols; ++j) out[j] = hnn_bias[l] ? hnn_bias[l][j] : 0.0;
  for (i = 0; i < rows; ++i)
    for (j = 0; j < cols; ++j) out[j] += in[i] * w[i * cols + j];
}

/* The forward pass: hidden activations into acts (layer after layer), H returned. */
static double hnn_forward(const double* x, double* acts) {
  const double* in = x;
  double h;
  int l, j;
  for (l = 0; l < HNN_HIDDEN; ++l) {
    double* a = acts + hnn_offset[l];
    hnn_affine(in, l, a);
    for (j = 0; j < hnn_width[l + 1]; ++j) a[j] = tanh(a[j]);
    in = a;
  }
  hnn_affine(in, HNN_HIDDEN, &h);
  return h;
}

double hnn_energy(const double* x) {
  double acts[HNN_ACTS];
  return hnn_forward(x, acts);
}

/* dH/dx by the backward pass: g = W_out, then g <- W_l (g * (1 - a_l^2)) down the layers. */
void hnn_gradient(const double* x, double* grad) {
  double acts[HNN_ACTS], g[HNN_WIDEST], below[HNN_WIDEST];
  int l, i, j;
  hnn_forward(x, acts);
  for (i = 0; i < hnn_width[HNN_HIDDEN]; ++i) g[i] = hnn_weight[HNN_HIDDEN][i];
  for (l = HNN_HIDDEN - 1; l >= 0; --l) {
    const double* a = acts + hnn_offset[l];
    const double* w = hnn_weight[l];
    const int rows = hnn_width[l], cols = hnn_width[l + 1];
    for (j = 0; j < cols; ++j) g[j] *= 1.0 - a[j] * a[j];
    for (i = 0; i < rows; ++i) {
      double s = 0.0;
      for (j = 0; j < cols; ++j) s += w[i * cols + j] * g[j];
      below[i] = s;
    }
    for (i = 0; i < rows; ++i) g[i] = below[i];
  }
  for (i = 0; i < HNN_DIM; ++i) grad[i] = g[i];
}

/* dx/dt = (dH/dp, -dH/dq). */
void hnn_field(const double* x, double* dxdt) {
  double grad[HNN_DIM];
  const int n = HNN_DIM / 2;
  int i;
  hnn_gradient(x, grad);
  for (i = 0; i < n; ++i) {
    dxdt[i] = grad[n + i];
    dxdt[n + i] = -grad[i];
  }
}
)";

std::string export_c(const DynamicsModel<double>& model, std::string_view source) {
  return c_header(model, source) + c_tables(model.mlp()) + kCFunctions;
}

// ---- JSON -------------------------------------------------------------------------------

std::string json_matrix(const Matrix<double>& m) {
  std::string rows;
  for (Index i = 0; i < m.rows(); ++i) {
    std::string row;
    for (Index j = 0; j < m.cols(); ++j) row += (j ? ", " : "") + number(m(i, j));
    rows += fmt::format("{}[{}]", i ? ",\n        " : "", row);
  }
  return "[" + rows + "]";
}

std::string json_layer(const Linear<double>& layer) {
  const std::string bias =
      layer.has_bias() ? "[" + flat_values(layer.bias().value()) + "]" : std::string("null");
  return fmt::format("    {{\"weight\": {},\n     \"bias\": {}}}",
                     json_matrix(layer.weight().value()), bias);
}

std::string json_input(Index dim) {
  std::string names;
  for (Index i = 0; i < dim; ++i) {
    names += fmt::format("{}\"{}{}\"", i ? ", " : "", i < dim / 2 ? "q" : "p", i % (dim / 2) + 1);
  }
  return "[" + names + "]";
}

std::string export_json(const DynamicsModel<double>& model, std::string_view source) {
  std::string layers;
  for (const Linear<double>& layer : model.mlp().layers()) {
    layers += (layers.empty() ? "" : ",\n") + json_layer(layer);
  }
  return fmt::format(
      "{{\n  \"format\": \"hnn-export\",\n  \"version\": 1,\n  \"source\": \"{}\",\n"
      "  \"model\": \"{}\",\n  \"field\": \"{}\",\n  \"activation\": \"tanh\",\n"
      "  \"dim\": {},\n  \"input\": {},\n  \"formula\": \"{}\",\n  \"layers\": [\n{}\n  ]\n}}\n",
      clean_source(source), model.describe(), to_string(model.config().field), model.dim(),
      json_input(model.dim()), kFormula, layers);
}

}  // namespace

ExportFormat parse_export_format(std::string_view name) {
  if (const std::optional<ExportFormat> format = find_name(kExportFormatNames, name)) {
    return *format;
  }
  throw std::invalid_argument(
      fmt::format("unknown export format '{}' (known: {})", name, join_names(kExportFormatNames)));
}

void check_exportable(const DynamicsModel<double>& model) {
  const DynamicsConfig& config = model.config();
  if (!learns_scalars(config.model) || !dynamic_cast<const Hnn<double>*>(&model)) {
    throw std::invalid_argument(fmt::format("cannot export a {} model: {}", model.name(),
                                            config.model == ModelKind::kBaseline
                                                ? "it has no learned H"
                                                : "export writes an HNN's H, one MLP of (q, p)"));
  }
  if (config.field != FieldType::kSolenoidal) {
    throw std::invalid_argument(fmt::format(
        "cannot export a {} HNN: only the solenoidal HNN (one H) is supported", model.name()));
  }
  if (config.activation != Activation::kTanh) {
    throw std::invalid_argument(fmt::format("cannot export activation '{}': only tanh is supported",
                                            to_string(config.activation)));
  }
  for (const Linear<double>& layer : model.mlp().layers()) {
    if (!all_finite(layer.weight().value()) ||
        (layer.has_bias() && !all_finite(layer.bias().value()))) {
      throw std::invalid_argument("cannot export a model with non-finite weights");
    }
  }
}

std::string export_model(const DynamicsModel<double>& model, ExportFormat format,
                         std::string_view source) {
  check_exportable(model);
  return format == ExportFormat::kC ? export_c(model, source) : export_json(model, source);
}

}  // namespace hnn::nn
