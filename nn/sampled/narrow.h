#pragma once
// The narrow products of LSQR's iterations on the Hadamard system, D (N x w, tall) against a few
// (dim) columns: p = D y^T and q^T = p^T D. Both are bound by reading D from memory once, which
// OpenBLAS's GEMM does not do (it first copies D into packed panels) and Eigen's GEMV does not
// either for q^T (it reads p again for every column of D). Each result entry is summed by one
// thread in a fixed order, so the bits do not depend on the thread count.

#include "nn/sampled/blas.h"

namespace hnn::nn::sampled {

/// p = D y^T: p N x dim (sized), y dim x w.
void narrow_product(const ColMat& d, const ColMat& y, ColMat& p);

/// qt = p^T D: qt dim x w (sized), p N x dim.
void narrow_product_t(const ColMat& d, const ColMat& p, ColMat& qt);

}  // namespace hnn::nn::sampled
