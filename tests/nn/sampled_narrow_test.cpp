// The narrow products of the Hadamard system's LSQR iterations (nn/sampled/narrow.h).

#include <gtest/gtest.h>

#include "autodiff/parallel.h"
#include "nn/sampled/narrow.h"

namespace hnn::nn::sampled {
namespace narrow_test {

using Eigen::Index;

struct Shape {
  Index rows, width, dim;
};

// Sizes off every multiple the kernels step by: rows not a whole packet or row unit, widths not
// a whole group of columns, dims above and below the kernels' 4.
// {3000, 5, 3}: four times its rows (the bits test's) span more than one piece of p at 3 dims.
constexpr Shape kShapes[] = {{1, 1, 1},     {7, 5, 2},     {130, 9, 3},
                             {1027, 13, 4}, {2500, 17, 6}, {3000, 5, 3}};

ColMat random(Index rows, Index cols, unsigned seed) {
  std::srand(seed);
  return ColMat::Random(rows, cols);
}

TEST(SampledNarrow, ProductsAgreeWithEigensOnEveryShape) {
  for (const Shape& s : kShapes) {
    const ColMat d = random(s.rows, s.width, 1), y = random(s.dim, s.width, 2),
                 p = random(s.rows, s.dim, 3);
    ColMat dy(s.rows, s.dim), ptd(s.dim, s.width);
    narrow_product(d, y, dy);
    narrow_product_t(d, p, ptd);
    const ColMat want_dy = d * y.transpose(), want_ptd = p.transpose() * d;
    EXPECT_LT((dy - want_dy).norm(), 1e-14 * want_dy.norm() * double(s.width)) << s.rows;
    EXPECT_LT((ptd - want_ptd).norm(), 1e-14 * want_ptd.norm() * double(s.rows)) << s.rows;
  }
}

TEST(SampledNarrow, GiveTheSameBitsOnOneThreadAndTwo) {
  const int threads = ad::num_threads();
  for (const Shape& s : kShapes) {
    const ColMat d = random(s.rows * 4, s.width * 3, 4), y = random(s.dim, s.width * 3, 5),
                 p = random(s.rows * 4, s.dim, 6);
    ColMat dy[2], ptd[2];
    for (int t : {1, 2}) {
      ad::set_num_threads(t);
      dy[t - 1].resize(d.rows(), s.dim);
      ptd[t - 1].resize(s.dim, d.cols());
      narrow_product(d, y, dy[t - 1]);
      narrow_product_t(d, p, ptd[t - 1]);
    }
    EXPECT_TRUE(dy[0] == dy[1]) << s.rows;
    EXPECT_TRUE(ptd[0] == ptd[1]) << s.rows;
  }
  ad::set_num_threads(threads);
}

}  // namespace narrow_test
}  // namespace hnn::nn::sampled
