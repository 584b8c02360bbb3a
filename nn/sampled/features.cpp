#include "nn/sampled/features.h"

#include <algorithm>
#include <cmath>

#include "autodiff/parallel.h"
#include "autodiff/tanh_kernel.h"

namespace hnn::nn::sampled {

using Eigen::Index;

ColMat mlp_input(const DynamicsConfig& config, const ColMat& x) {
  const Index a = config.angles, dim = config.dim;
  ColMat u(x.rows(), dim + a);
  for (Index i = 0; i < a; ++i) {
    u.col(i) = x.col(i).array().cos();
    u.col(a + i) = x.col(i).array().sin();
  }
  for (Index i = a; i < dim; ++i) {
    const double scale = config.input_scale.empty() ? 1.0 : config.input_scale[std::size_t(i)];
    u.col(a + i) = x.col(i) / scale;
  }
  return u;
}

namespace {

// act and act' of one value; f and df may be one double (activate in place): f is written
// first, and df reads only t and f.
void activate_one(Activation activation, double t, double& f, double& df) {
  constexpr double kSeluAlpha = 1.6732632423543772, kSeluScale = 1.0507009873554805;
  switch (activation) {
    case Activation::kTanh:
      f = std::tanh(t);
      df = 1 - f * f;
      return;
    case Activation::kRelu:
      f = t > 0 ? t : 0;
      df = t > 0 ? 1 : 0;
      return;
    case Activation::kSigmoid:
      f = 1 / (1 + std::exp(-t));
      df = f * (1 - f);
      return;
    case Activation::kSoftplus:
      f = t > 0 ? t + std::log1p(std::exp(-t)) : std::log1p(std::exp(t));
      df = 1 / (1 + std::exp(-t));
      return;
    case Activation::kElu:
      f = t > 0 ? t : std::expm1(t);
      df = t > 0 ? 1 : std::exp(t);
      return;
    case Activation::kSelu:
      f = kSeluScale * (t > 0 ? t : kSeluAlpha * std::expm1(t));
      df = kSeluScale * (t > 0 ? 1 : kSeluAlpha * std::exp(t));
      return;
    case Activation::kSwish: {
      const double s = 1 / (1 + std::exp(-t));
      f = t * s;
      df = s + t * s * (1 - s);
      return;
    }
  }
}

}  // namespace

// Split over the engine's threads: a width-5000 layer on 20k points is 1e8 tanh.
void activate(Activation activation, const ColMat& z, ColMat& value, ColMat* slope) {
  value.resize(z.rows(), z.cols());
  if (slope) slope->resize(z.rows(), z.cols());
  const int parts = ad::parts_for(z.size(), 1 << 14);
  ad::parallel_for(parts, [&](int part) {
    const ad::RowBlock block = ad::row_block(z.size(), parts, part);
    if (activation == Activation::kTanh) {      // the engine's vectorised kernel: libm's scalar
      const Index n = block.end - block.begin;  // tanh was most of a fit's assembly
      ad::detail::tanh_values(z.data() + block.begin, value.data() + block.begin, n);
      if (slope) {
        slope->reshaped().segment(block.begin, n) =
            1 - value.reshaped().segment(block.begin, n).array().square();
      }
      return;
    }
    double df = 0;
    for (Index k = block.begin; k < block.end; ++k) {
      activate_one(activation, z.data()[k], value.data()[k], slope ? slope->data()[k] : df);
    }
  });
}

ColMat pre_activation(const HiddenLayer& layer, const ColMat& u) {
  ColMat z(u.rows(), layer.w.cols());
  blas_gemm(u, false, layer.w, false, z);
  z.rowwise() += layer.b;
  return z;
}

std::vector<std::vector<FieldTerm>> field_terms(const DynamicsConfig& config) {
  const Index dim = config.dim, dof = dim / 2;
  std::vector<FieldTerm> solenoidal, conservative;
  for (Index i = 0; i < dim; ++i) {
    solenoidal.push_back(i < dof ? FieldTerm{dof + i, 1.0} : FieldTerm{i - dof, -1.0});
    conservative.push_back(FieldTerm{i, 1.0});
  }
  switch (config.field) {
    case FieldType::kSolenoidal:
      return {solenoidal};
    case FieldType::kConservative:
      return {conservative};
    case FieldType::kBoth:
      break;
  }
  return {solenoidal, conservative};
}

namespace {

// d u / d x_i at points [n0, n0 + rows) of x, stacked: row i * rows + k (rows x cols of u).
ColMat input_tangents(const DynamicsConfig& config, const ColMat& x, Index n0, Index rows) {
  const Index a = config.angles, dim = config.dim;
  ColMat t = ColMat::Zero(dim * rows, dim + a);
  for (Index i = 0; i < dim; ++i) {
    for (Index k = 0; k < rows; ++k) {
      if (i < a) {
        t(i * rows + k, i) = -std::sin(x(n0 + k, i));
        t(i * rows + k, a + i) = std::cos(x(n0 + k, i));
      } else {
        t(i * rows + k, a + i) =
            config.input_scale.empty() ? 1.0 : 1.0 / config.input_scale[std::size_t(i)];
      }
    }
  }
  return t;
}

}  // namespace

ColMat field_matrix(const DynamicsConfig& config, const std::vector<HiddenLayer>& layers,
                    const ColMat& x) {
  const Index n = x.rows(), dim = config.dim, width = layers.back().w.cols();
  const auto terms = field_terms(config);
  ColMat a(n * dim, Index(terms.size()) * width);
  Index widest = 1;
  for (const HiddenLayer& layer : layers) widest = std::max(widest, layer.w.cols());
  const Index block = std::max<Index>(1, (Index(1) << 22) / (dim * widest));
  ColMat value, slope, z, next;
  for (Index n0 = 0; n0 < n; n0 += block) {
    const Index rows = std::min(block, n - n0);
    ColMat h = mlp_input(config, x.middleRows(n0, rows));
    ColMat t = input_tangents(config, x, n0, rows);
    for (const HiddenLayer& layer : layers) {
      z = pre_activation(layer, h);
      activate(config.activation, z, value, &slope);
      next.resize(t.rows(), layer.w.cols());
      blas_gemm(t, false, layer.w, false, next);
      for (Index i = 0; i < dim; ++i) next.middleRows(i * rows, rows).array() *= slope.array();
      t.swap(next);
      h.swap(value);
    }
    for (std::size_t s = 0; s < terms.size(); ++s) {
      for (Index i = 0; i < dim; ++i) {
        const FieldTerm term = terms[s][std::size_t(i)];
        a.block(i * n + n0, Index(s) * width, rows, width) =
            term.sign * t.middleRows(term.source * rows, rows);
      }
    }
  }
  return a;
}

}  // namespace hnn::nn::sampled
