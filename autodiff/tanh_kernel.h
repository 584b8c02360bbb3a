#pragma once
// Internal: the engine's one tanh kernel, used by the elementwise op (ad::tanh) and by the fused
// MLP kernels, so that both give the same bits for the same input.
//
// Every element goes through Eigen's packet (SIMD) functions. Eigen computes the part of a
// buffer before its first aligned address, and a tail shorter than a packet, with its scalar
// functions (std::exp for double, a scalar tanh for float), which round differently, so a value
// would depend on where it sits in memory: on the row block a thread got, or on whether the
// batch went through a fused op. Here the 64-byte-aligned bulk of the output is computed in
// place, and the unaligned head and the short tail in an aligned buffer of one 64-byte line.

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <type_traits>

namespace hnn::ad::detail {

/// dst = tanh(src). Float: Eigen's vectorised tanh. Double: Eigen calls the scalar libm tanh,
/// which dominated HNN training; 2 / (1 + e^-2x) - 1 on the vectorised exp instead (absolute
/// error a few ulps of 1; saturates correctly at +-1, e^-2x -> 0 or inf).
template <typename Dst, typename Src>
void tanh_formula(Dst&& dst, const Src& src) {
  using T = typename std::decay_t<Dst>::Scalar;
  if constexpr (std::is_same_v<T, float>) {
    dst = src.tanh();
  } else {
    dst = T(2) / (T(1) + (T(-2) * src).exp()) - T(1);
  }
}

/// Elements per 64-byte line: a multiple of every SIMD width, for both types.
template <typename T>
inline constexpr Eigen::Index kLine = 64 / Eigen::Index(sizeof(T));

/// out[i] = tanh(x[i]) for i < n <= kLine<T>, through an aligned line (every lane a packet lane).
template <typename T>
void tanh_through_line(const T* x, T* out, Eigen::Index n) {
  if (n == 0) return;
  alignas(64) Eigen::Array<T, kLine<T>, 1> line = Eigen::Array<T, kLine<T>, 1>::Zero();
  line.head(n) = Eigen::Map<const Eigen::Array<T, Eigen::Dynamic, 1>>(x, n);
  tanh_formula(line, line);
  Eigen::Map<Eigen::Array<T, Eigen::Dynamic, 1>>(out, n) = line.head(n);
}

/// out[i] = tanh(x[i]) for i < n; out may be x (in place). Both are contiguous.
template <typename T>
void tanh_values(const T* x, T* out, Eigen::Index n) {
  using Array = Eigen::Array<T, Eigen::Dynamic, 1>;
  const auto misalignment = Eigen::Index(reinterpret_cast<std::uintptr_t>(out) % 64 / sizeof(T));
  const Eigen::Index head = std::min(n, (kLine<T> - misalignment) % kLine<T>);
  const Eigen::Index bulk = (n - head) / kLine<T> * kLine<T>;
  tanh_through_line(x, out, head);
  Eigen::Map<Array, Eigen::Aligned64> aligned(out + head, bulk);
  tanh_formula(aligned, Eigen::Map<const Array>(x + head, bulk));
  tanh_through_line(x + head + bulk, out + head + bulk, n - head - bulk);
}

/// tanh in place on a contiguous block (a matrix, or a row block of a row-major matrix).
template <typename Block>
void tanh_in_place(Block&& z) {
  eigen_assert(z.rows() <= 1 || z.outerStride() == z.cols());
  tanh_values(z.data(), z.data(), z.size());
}

}  // namespace hnn::ad::detail
