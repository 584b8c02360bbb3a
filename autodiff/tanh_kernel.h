#pragma once
// Internal: the engine's one tanh kernel, used by the elementwise op (ad::tanh) and by the fused
// MLP kernels, so that both give the same bits for the same input.
//
// Every element goes through Eigen's packet (SIMD) functions: values are copied in chunks into
// an aligned buffer whose size is a multiple of every packet width, computed there, and copied
// back. Eigen would otherwise compute the unaligned head and the tail of a buffer with its
// scalar functions (std::exp for double, a scalar tanh for float), which round differently from
// the packet ones, so a value would depend on where it sits in memory: on the row block a
// thread got, or on whether the batch went through a fused op.

#include <Eigen/Core>
#include <algorithm>
#include <type_traits>

namespace hnn::ad::detail {

/// The formula on one aligned chunk. Float: Eigen's vectorised tanh. Double: Eigen calls the
/// scalar libm tanh, which dominated HNN training; 2 / (1 + e^-2x) - 1 on the vectorised exp
/// instead (absolute error a few ulps of 1; saturates correctly at +-1, e^-2x -> 0 or inf).
template <typename Chunk>
void tanh_chunk(Chunk& z) {
  using T = typename Chunk::Scalar;
  if constexpr (std::is_same_v<T, float>) {
    z = z.tanh();
  } else {
    z = T(2) / (T(1) + (T(-2) * z).exp()) - T(1);
  }
}

/// out[i] = tanh(x[i]) for i < n; out may be x (in place). Both are contiguous.
template <typename T>
void tanh_values(const T* x, T* out, Eigen::Index n) {
  constexpr Eigen::Index kChunk = 64;  // a multiple of every SIMD width, for both types
  alignas(64) Eigen::Array<T, kChunk, 1> chunk;
  for (Eigen::Index i = 0; i < n; i += kChunk) {
    const Eigen::Index m = std::min(kChunk, n - i);
    chunk.head(m) = Eigen::Map<const Eigen::Array<T, Eigen::Dynamic, 1>>(x + i, m);
    if (m < kChunk) chunk.tail(kChunk - m).setZero();
    tanh_chunk(chunk);
    Eigen::Map<Eigen::Array<T, Eigen::Dynamic, 1>>(out + i, m) = chunk.head(m);
  }
}

/// tanh in place on a contiguous block (a matrix, or a row block of a row-major matrix).
template <typename Block>
void tanh_in_place(Block&& z) {
  eigen_assert(z.rows() <= 1 || z.outerStride() == z.cols());
  tanh_values(z.data(), z.data(), z.size());
}

}  // namespace hnn::ad::detail
