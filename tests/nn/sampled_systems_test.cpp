// The least-squares forms of the sampled fit (nn/sampled/systems.h): the Hadamard form of an
// HNN's one-hidden-layer system must equal the formed matrix.

#include <gtest/gtest.h>

#include <Eigen/QR>

#include "nn/sampled/features.h"
#include "nn/sampled/systems.h"

namespace hnn::nn::sampled {
namespace {

TEST(SampledSystems, HadamardGramEqualsTheFormedNormalMatrix) {
  for (int blocks : {1, 2}) {
    const Eigen::Index n = 40, w = 7, dim = 4;
    const ColMat d = ColMat::Random(n, w), v = ColMat::Random(dim, blocks * w);
    const ColMat dxdt = ColMat::Random(n, dim);
    const HadamardSystem system(d, v, dxdt);
    const ColMat a = system.formed();
    ASSERT_EQ(a.rows(), n * dim);
    ColMat g(blocks * w, blocks * w);
    system.gram(g);
    const ColMat want = a.transpose() * a;
    EXPECT_LT((g - want).cwiseAbs().maxCoeff(), 1e-13 * want.cwiseAbs().maxCoeff());
    const ColMat c = ColMat::Random(blocks * w, 1);
    ColMat ac(n * dim, 1), atr(blocks * w, 1);
    system.apply(c, ac);
    EXPECT_LT((ac - a * c).norm(), 1e-13 * ac.norm());
    system.apply_t(system.rhs(), atr);
    EXPECT_LT((atr - a.transpose() * system.rhs()).norm(), 1e-13 * atr.norm());
    // The reduction has A's least-squares solution.
    ColMat ra, rb;
    system.reduced(ra, rb);
    ASSERT_EQ(ra.rows(), blocks == 1 ? w : dim * w);  // one block: the triangles merged
    const ColMat want_c = a.colPivHouseholderQr().solve(system.rhs());
    const ColMat got_c = ra.colPivHouseholderQr().solve(rb);
    EXPECT_LT((got_c - want_c).norm(), 1e-10 * want_c.norm());
    // Row i * n + k of A is field coordinate i at point k: D row k scaled by v_i.
    EXPECT_DOUBLE_EQ(a(2 * n + 5, 3), d(5, 3) * v(2, 3));
    EXPECT_DOUBLE_EQ(system.rhs()(2 * n + 5, 0), dxdt(5, 2));
  }
}

// Fewer points than neurons: D has no square R, and the reduction is A itself (it was a LAPACK
// error before: `hnn train spring --fit sampled --hidden 1000` on 750 points).
TEST(SampledSystems, FewerPointsThanNeuronsReduceToTheFormedMatrix) {
  const Eigen::Index n = 5, w = 8, dim = 2;
  const HadamardSystem system(ColMat::Random(n, w), ColMat::Random(dim, w), ColMat::Random(n, dim));
  ColMat ra, rb;
  system.reduced(ra, rb);
  EXPECT_EQ(ra, system.formed());
  EXPECT_EQ(rb, system.rhs());
}

// The formed path (tangents through the layers) gives the Hadamard form's matrix for one layer,
// and matches central differences of the hidden outputs through the angle embedding.
TEST(SampledSystems, FormedFieldMatrixMatchesHadamardAndDifferences) {
  DynamicsConfig config;
  config.dim = 4;
  config.field = FieldType::kBoth;
  const ColMat x = ColMat::Random(30, 4);
  HiddenLayer layer{ColMat::Random(4, 6), Eigen::RowVectorXd::Random(6)};
  const ColMat formed = field_matrix(config, {layer}, x);
  ColMat value, slope;
  activate(config.activation, pre_activation(layer, x), value, &slope);
  ColMat v(4, 12);
  v << layer.w.row(2), layer.w.row(0), layer.w.row(3), layer.w.row(1), -layer.w.row(0),
      layer.w.row(2), -layer.w.row(1), layer.w.row(3);
  EXPECT_LT((formed - HadamardSystem(slope, v, ColMat::Zero(30, 4)).formed()).norm(), 1e-12);

  config.field = FieldType::kConservative;
  config.angles = 1;
  config.input_scale = {1.0, 2.0, 0.5, 3.0};
  const std::vector<HiddenLayer> deep{{ColMat::Random(5, 6), Eigen::RowVectorXd::Random(6)},
                                      {ColMat::Random(6, 3), Eigen::RowVectorXd::Random(3)}};
  const ColMat a = field_matrix(config, deep, x);
  auto hidden = [&](const ColMat& at) {
    ColMat h = mlp_input(config, at), out;
    for (const HiddenLayer& l : deep) {
      activate(config.activation, pre_activation(l, h), out, nullptr);
      h = out;
    }
    return h;
  };
  const double eps = 1e-6;
  for (Eigen::Index i = 0; i < 4; ++i) {
    ColMat up = x, down = x;
    up.col(i).array() += eps;
    down.col(i).array() -= eps;
    const ColMat numeric = (hidden(up) - hidden(down)) / (2 * eps);
    EXPECT_LT((a.middleRows(i * 30, 30) - numeric).cwiseAbs().maxCoeff(), 1e-8) << i;
  }
}

}  // namespace
}  // namespace hnn::nn::sampled
