#include "nn/sampled/narrow.h"

#include <algorithm>
#include <array>

#include "autodiff/parallel.h"

namespace hnn::nn::sampled {

using Eigen::Index;

namespace {

using Packet = Eigen::internal::packet_traits<double>::type;
constexpr Index kLanes = Eigen::internal::packet_traits<double>::size;

// Result columns (coordinates) a kernel call takes at most, and D's columns per call: p^T D
// keeps 4 x 4 accumulators in registers; D y^T keeps p's 4 in registers across 8 columns of D.
// Every element of D is loaded once.
constexpr int kDims = 4;
constexpr int kDotColumns = 4;
constexpr int kAxpyColumns = 8;
constexpr int kMaxColumns = std::max(kDotColumns, kAxpyColumns);
using Columns = std::array<const double*, kMaxColumns>;

// out(i, c) = p_i . d_c over rows [0, n), for C columns and D dims; out column-major (ldo).
// Lanes accumulate separately and are summed at the end, then the rows after the last packet.
template <int C, int D>
void dots(const Columns& d, const std::array<const double*, kDims>& p, Index n, double* out,
          Index ldo) {
  using namespace Eigen::internal;
  Packet acc[C][D];
  for (int c = 0; c < C; ++c) {
    for (int i = 0; i < D; ++i) acc[c][i] = pset1<Packet>(0.0);
  }
  Index r = 0;
  for (; r + kLanes <= n; r += kLanes) {
    Packet pv[D];
    for (int i = 0; i < D; ++i) pv[i] = ploadu<Packet>(p[i] + r);
    for (int c = 0; c < C; ++c) {
      const Packet dv = ploadu<Packet>(d[c] + r);
      for (int i = 0; i < D; ++i) acc[c][i] = pmadd(dv, pv[i], acc[c][i]);
    }
  }
  for (int c = 0; c < C; ++c) {
    for (int i = 0; i < D; ++i) {
      double sum = predux(acc[c][i]);
      for (Index t = r; t < n; ++t) sum += d[c][t] * p[i][t];
      out[c * ldo + i] = sum;
    }
  }
}

// p_i[r0, r0 + len) += sum_c y(i, c) d_c for C columns and D dims (y column-major, ldy).
template <int C, int D>
void axpys(const Columns& d, const double* y, Index ldy, const std::array<double*, kDims>& p,
           Index r0, Index len) {
  using namespace Eigen::internal;
  Index r = r0;
  for (; r + kLanes <= r0 + len; r += kLanes) {
    Packet acc[D];
    for (int i = 0; i < D; ++i) acc[i] = ploadu<Packet>(p[i] + r);
    for (int c = 0; c < C; ++c) {
      const Packet dv = ploadu<Packet>(d[c] + r);
      for (int i = 0; i < D; ++i) acc[i] = pmadd(dv, pset1<Packet>(y[c * ldy + i]), acc[i]);
    }
    for (int i = 0; i < D; ++i) pstoreu(p[i] + r, acc[i]);
  }
  for (; r < r0 + len; ++r) {
    for (int i = 0; i < D; ++i) {
      double sum = p[i][r];
      for (int c = 0; c < C; ++c) sum += d[c][r] * y[c * ldy + i];
      p[i][r] = sum;
    }
  }
}

// f.template operator()<D>() for a runtime count of dims in [1, kDims].
template <typename F>
void with_dims(int dims, F&& f) {
  switch (dims) {
    case 1:
      return f.template operator()<1>();
    case 2:
      return f.template operator()<2>();
    case 3:
      return f.template operator()<3>();
    default:
      return f.template operator()<4>();
  }
}

// Columns i0 .. i0 + kDims of p (fewer at its end): one kernel call's coordinates.
template <typename Pointer, typename Matrix>
std::array<Pointer, kDims> dims_of(Matrix& p, Index i0) {
  std::array<Pointer, kDims> out{};
  for (Index i = i0; i < std::min(p.cols(), i0 + kDims); ++i)
    out[std::size_t(i - i0)] = p.col(i).data();
  return out;
}

Columns columns_of(const ColMat& d, Index k, int count) {
  Columns out{};
  for (int c = 0; c < count; ++c) out[std::size_t(c)] = d.col(k + c).data();
  return out;
}

// Rows are split between threads, and a thread's rows into pieces, in whole units of this many,
// so that only D's last rows, past the last whole packet, take the scalar tail, whatever the
// thread count.
constexpr Index kRowUnit = 64;

// Rows of p a thread updates per pass over D's columns: p's piece (rows x dim) stays in L2
// (256 KB) while D's columns stream through, in pieces long enough to span pages (at 20000 x
// 3000 on a 2-core Zen 3, pieces of 512 rows ran 1.4-1.8x slower than of 4096).
Index piece_rows(Index dims) {
  const Index rows = std::max<Index>(1024, 32768 / std::max<Index>(dims, 1));
  return rows / kRowUnit * kRowUnit;
}

}  // namespace

void narrow_product(const ColMat& d, const ColMat& y, ColMat& p) {
  const Index n = d.rows(), w = d.cols(), dim = y.rows();
  const Index units = (n + kRowUnit - 1) / kRowUnit;
  const int parts = int(std::clamp<Index>(units / 16, 1, ad::num_threads()));
  ad::parallel_for(parts, [&](int part) {
    const ad::RowBlock mine = ad::row_block(units, parts, part);
    const Index begin = mine.begin * kRowUnit, end = std::min(n, mine.end * kRowUnit);
    const Index step = piece_rows(dim);
    for (Index r0 = begin; r0 < end; r0 += step) {
      const Index len = std::min(step, end - r0);
      p.middleRows(r0, len).setZero();
      for (Index i0 = 0; i0 < dim; i0 += kDims) {
        const auto pi = dims_of<double*>(p, i0);
        with_dims(int(std::min<Index>(kDims, dim - i0)), [&]<int D>() {
          Index k = 0;
          for (; k + kAxpyColumns <= w; k += kAxpyColumns) {
            axpys<kAxpyColumns, D>(columns_of(d, k, kAxpyColumns), y.data() + k * dim + i0, dim, pi,
                                   r0, len);
          }
          for (; k < w; ++k)
            axpys<1, D>(columns_of(d, k, 1), y.data() + k * dim + i0, dim, pi, r0, len);
        });
      }
    }
  });
}

void narrow_product_t(const ColMat& d, const ColMat& p, ColMat& qt) {
  const Index n = d.rows(), w = d.cols(), dim = p.cols();
  const Index groups = (w + kDotColumns - 1) / kDotColumns;
  const int parts = int(std::min<Index>(groups, ad::num_threads()));
  ad::parallel_for(parts, [&](int part) {
    const ad::RowBlock mine = ad::row_block(groups, parts, part);
    const Index begin = mine.begin * kDotColumns, end = std::min(w, mine.end * kDotColumns);
    for (Index i0 = 0; i0 < dim; i0 += kDims) {
      const auto pi = dims_of<const double*>(p, i0);
      with_dims(int(std::min<Index>(kDims, dim - i0)), [&]<int D>() {
        Index k = begin;
        for (; k + kDotColumns <= end; k += kDotColumns) {
          dots<kDotColumns, D>(columns_of(d, k, kDotColumns), pi, n, qt.col(k).data() + i0,
                               qt.rows());
        }
        for (; k < end; ++k)
          dots<1, D>(columns_of(d, k, 1), pi, n, qt.col(k).data() + i0, qt.rows());
      });
    }
  });
}

}  // namespace hnn::nn::sampled
