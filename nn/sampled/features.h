#pragma once
// What the sampled hidden layers compute, in double: the MLP's input map (DynamicsModel::
// mlp_input), the layers' values and slopes, and the tangents d h / d x carried through them.

#include <vector>

#include "nn/activation.h"
#include "nn/dynamics.h"
#include "nn/sampled/blas.h"

namespace hnn::nn::sampled {

/// A hidden layer h = act(u w + b): w is in x out, b 1 x out (Linear's layout).
struct HiddenLayer {
  ColMat w;
  Eigen::RowVectorXd b;
};

/// The MLP's input for states x (N x dim): x / scale, each angle as (cos, sin) (columns: cos of
/// the angles, sin of the angles, the other coordinates), as DynamicsModel::mlp_input.
ColMat mlp_input(const DynamicsConfig& config, const ColMat& x);

/// act(z) and act'(z) of the activation, elementwise; `slope` may be null, `value` may be z, and
/// so may both: z then ends as act'(z) (an HNN's system needs the slope alone, and at width 3000
/// on 20k points the values would be another 480 MB).
void activate(Activation activation, const ColMat& z, ColMat& value, ColMat* slope);

/// The pre-activation u w + b of a layer.
ColMat pre_activation(const HiddenLayer& layer, const ColMat& u);

/// The field's rows in terms of the last hidden layer's input gradients: field coordinate i,
/// column block s (0: H's columns, 1: D's for field type both) reads `sign` times the gradient
/// along state coordinate `source`.
struct FieldTerm {
  Eigen::Index source;
  double sign;
};
/// terms[s][i] for the model's field type: solenoidal f_q = dH/dp, f_p = -dH/dq; conservative
/// f = dD/dx; both: the two blocks.
std::vector<std::vector<FieldTerm>> field_terms(const DynamicsConfig& config);

/// The formed field matrix of an HNN whose MLP has the given hidden layers: rows i * N + n
/// (field coordinate i at point n), columns s * width + j. Tangents d u / d x are carried
/// through every layer in blocks of points, so the work memory stays bounded.
ColMat field_matrix(const DynamicsConfig& config, const std::vector<HiddenLayer>& layers,
                    const ColMat& x);

}  // namespace hnn::nn::sampled
