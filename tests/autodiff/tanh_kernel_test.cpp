// One tanh kernel: the elementwise op and the fused MLP kernels give the same bits, whatever the
// batch size, the thread count (row blocks start anywhere in memory) or the scalar type.

#include "autodiff/tanh_kernel.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "autodiff/autodiff.h"
#include "test_util.h"

namespace ad = hnn::ad;
using ad::Var;
using ad::testing::random_matrix;

namespace {

// A hidden layer through the fused op: tanh_mlp(x, {W, I}) = tanh(x W + b) I, and multiplying by
// the identity is exact, so the fused op's output is its hidden layer's tanh values.
template <typename T>
ad::Matrix<T> fused_hidden_layer(const Var<T>& x, const Var<T>& w, const Var<T>& b) {
  const Var<T> identity = Var<T>::constant(ad::Matrix<T>::Identity(w.cols(), w.cols()));
  return ad::tanh_mlp<T>(x, {w, identity}, {b, Var<T>()}).value();
}

template <typename T>
void expect_fused_and_generic_tanh_identical() {
  for (int threads : {1, 2}) {
    ad::set_num_threads(threads);
    for (Eigen::Index rows : {1, 7, 150, 333}) {
      ad::TapeScope scope;
      const Var<T> x = Var<T>::leaf(random_matrix(rows, 3, 31, -3, 3).cast<T>());
      const Var<T> w = Var<T>::leaf(random_matrix(3, 21, 32).cast<T>());
      const Var<T> b = Var<T>::leaf(random_matrix(1, 21, 33).cast<T>());
      const ad::Matrix<T> generic = ad::tanh(ad::linear(x, w, b)).value();
      EXPECT_EQ(fused_hidden_layer(x, w, b), generic) << rows << " rows, " << threads << " threads";
    }
  }
  ad::set_num_threads(2);
}

TEST(TanhKernel, FusedAndGenericForwardGiveBitIdenticalValues) {
  expect_fused_and_generic_tanh_identical<double>();
  expect_fused_and_generic_tanh_identical<float>();
}

// Eigen computes the unaligned head and the short tail of a buffer with scalar functions; for
// double they round differently from the packet ones on about 1.6% of inputs, so 1000 inputs
// alone (1x1, all "tail") and shifted against the packet boundaries catch a kernel that lets
// Eigen choose.
template <typename T>
void expect_position_independent() {
  ad::TapeScope scope;
  const ad::Matrix<T> x = random_matrix(1, 1000, 34, -4, 4).cast<T>();
  const ad::Matrix<T> whole = ad::tanh(Var<T>::constant(x)).value();
  for (Eigen::Index start : {1, 3, 67}) {
    const ad::Matrix<T> part = x.rightCols(x.cols() - start);
    EXPECT_EQ(ad::tanh(Var<T>::constant(part)).value(), whole.rightCols(x.cols() - start))
        << "from column " << start;
  }
  int differ = 0;
  for (Eigen::Index i = 0; i < x.cols(); ++i) {
    differ += ad::tanh(Var<T>::constant(x.col(i))).value()(0, 0) != whole(0, i);
  }
  EXPECT_EQ(differ, 0) << "of " << x.cols() << " elements computed alone";
}

TEST(TanhKernel, ValueDoesNotDependOnWhereTheElementSits) {
  expect_position_independent<double>();
  expect_position_independent<float>();
}

TEST(TanhKernel, SaturatesAndPropagatesNan) {
  ad::TapeScope scope;
  const double inf = std::numeric_limits<double>::infinity();
  ad::Matrix<double> x(1, 6);
  x << -inf, -800, -20, 20, 800, inf;
  const ad::Matrix<double> y = ad::tanh(Var<double>::constant(x)).value();
  for (Eigen::Index i = 0; i < 6; ++i) EXPECT_EQ(y(0, i), x(0, i) < 0 ? -1.0 : 1.0) << x(0, i);
  ad::Matrix<double> nan(1, 1);
  nan << std::nan("");
  EXPECT_TRUE(std::isnan(ad::tanh(Var<double>::constant(nan)).value()(0, 0)));
}

// Double precision: within a few ulps of 1 of the true tanh everywhere (the formulas subtract
// from 1, so a tiny tanh(x) ~ x is good to an absolute 1e-16, not to its own last bit), and
// increasing where neighbouring points differ by more than that.
TEST(TanhKernel, DoubleIsWithinAFewUlpsOfOneOfTheTrueTanh) {
  ad::TapeScope scope;
  ad::Matrix<double> x(1, 4001);
  for (Eigen::Index i = 0; i < x.cols(); ++i) {
    const double u = double(i - 2000) / 2000.0;                              // -1..1
    x(0, i) = std::copysign(std::pow(10.0, -12.0 + 13.5 * std::abs(u)), u);  // up to 10^1.5
  }
  const ad::Matrix<double> y = ad::tanh(Var<double>::constant(x)).value();
  double worst = 0;
  for (Eigen::Index i = 0; i < x.cols(); ++i) {
    const long double truth = std::tanh(static_cast<long double>(x(0, i)));
    worst = std::max(worst, double(std::abs(static_cast<long double>(y(0, i)) - truth)));
    if (i > 0 && std::abs(x(0, i)) < 5) {
      EXPECT_LT(y(0, i - 1), y(0, i)) << x(0, i);
    }
  }
  EXPECT_LT(worst, 4 * std::numeric_limits<double>::epsilon());
}

// A machine with AVX-512 computes double tanh 8 lanes at a time, one with AVX2 alone 4 at a time:
// the same operations lane by lane, so a model gives the same bits on either.
TEST(TanhKernel, EightLanesAndFourGiveTheSameBits) {
#if defined(HNN_SIMD_DOUBLE_TANH) && defined(EIGEN_VECTORIZE_AVX512)
  namespace d = ad::detail;
  const double inf = std::numeric_limits<double>::infinity();
  ad::Matrix<double> x = random_matrix(1, 4096, 35, -25, 25);
  const double special[] = {0.0, -0.0, 1e-300, -1e-17, 19.9, 20.1, -800, inf, -inf, std::nan("")};
  for (std::size_t i = 0; i < std::size(special); ++i) x(0, Eigen::Index(i)) = special[i];
  alignas(64) double four[8], eight[8];
  int differ = 0;
  for (Eigen::Index i = 0; i < x.cols(); i += 8) {
    const double* in = x.data() + i;
    for (int half : {0, 4}) {
      d::Avx2Doubles::store(four + half,
                            d::tanh_packet<d::Avx2Doubles>(d::Avx2Doubles::load(in + half)));
    }
    d::Avx512Doubles::store(eight, d::tanh_packet<d::Avx512Doubles>(d::Avx512Doubles::load(in)));
    differ += std::memcmp(four, eight, sizeof four) != 0;
  }
  EXPECT_EQ(differ, 0) << "of " << x.cols() / 8 << " packets of 8";
#else
  GTEST_SKIP() << "this build has no AVX-512 double tanh";
#endif
}

}  // namespace
