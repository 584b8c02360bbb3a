#pragma once
// The gradients the finite-difference chart studies, each with a long-double reference: dH/dx of
// the pendulum, of the two-body problem and of a trained HNN, and the HNN loss's gradient with
// respect to the parameters. Plus the finite-difference and autodiff routines that are timed.

#include <functional>
#include <string>
#include <vector>

#include "bench/accuracy/common.h"

namespace hnn::accuracy {

/// Relative errors of one-sided (forward) and central differences at one step h.
struct FdErrors {
  double forward = 0, central = 0;
};

/// One gradient to approximate. Errors are max |g - g_ref| / max |g_ref| over every evaluated
/// point and coordinate, against a long-double reference.
struct GradientCase {
  std::string name;
  int points = 0;         // states (rows) the gradient is evaluated at
  int coordinates = 0;    // coordinates differentiated per point
  std::string reference;  // "analytic" or "hand-derived MLP backprop" (both in long double)
  double ad_double_error = 0, ad_float_error = 0;
  std::function<FdErrors(double h)> fd_errors;
};

/// pendulum_H, two_body_H, hnn_H (a 2-200-200-1 HNN trained on spring data) and
/// hnn_loss_params (a 2-200-200-1 HNN at initialisation, 8 sampled coordinates per parameter
/// tensor). quick: less training and fewer coordinates.
std::vector<GradientCase> gradient_cases(bool quick);

/// f maps a batch (R x d) to one value per row (R x 1); returns the R x d gradient by one-sided
/// ((f(x + h e_j) - f(x)) / h, d + 1 calls) or central ((f(x + h e_j) - f(x - h e_j)) / 2h,
/// 2d calls) differences, perturbing column j of every row at once.
using BatchFunction = std::function<nn::Matrix<double>(const nn::Matrix<double>&)>;
nn::Matrix<double> finite_difference_gradient(const BatchFunction& f, const nn::Matrix<double>& x,
                                              double h, bool central);

/// The HNN loss mse(time_derivative(x), dxdt), values only.
double hnn_loss(const nn::Hnn<double>& model, const SpringData& data);
/// Its gradient with respect to every parameter by reverse mode (parameter order).
template <typename T>
std::vector<nn::Matrix<T>> hnn_loss_autodiff(const nn::Hnn<T>& model, const SpringData& data);
/// The same by finite differences over every parameter (changes each and restores it).
std::vector<nn::Matrix<double>> loss_fd_gradient(nn::Hnn<double>& model, const SpringData& data,
                                                 double h, bool central);

}  // namespace hnn::accuracy
