#pragma once
// Internal: the engine's one tanh kernel, used by the elementwise op (ad::tanh) and by the fused
// MLP kernels, so that both give the same bits for the same input.
//
// Every element goes through packet (SIMD) code: Eigen's, or tanh_packet for double. Eigen
// computes the part of a buffer before its first aligned address, and a tail shorter than a
// packet, with its scalar functions (std::exp for double, a scalar tanh for float), which round
// differently, so a value would depend on where it sits in memory: on the row block a thread
// got, or on whether the batch went through a fused op. Here the 64-byte-aligned bulk of the
// output is computed in place, and the unaligned head and the short tail in an aligned buffer of
// one 64-byte line.

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <type_traits>

#if defined(EIGEN_VECTORIZE_AVX2) && defined(EIGEN_VECTORIZE_FMA)
#include <immintrin.h>
#define HNN_SIMD_DOUBLE_TANH 1
#endif

namespace hnn::ad::detail {

#ifdef HNN_SIMD_DOUBLE_TANH
/// The instructions tanh_packet needs, on 4 doubles (AVX2 and FMA).
struct Avx2Doubles {
  using V = __m256d;
  static constexpr int kWidth = 4;
  static V set(double v) { return _mm256_set1_pd(v); }
  static V load(const double* p) { return _mm256_loadu_pd(p); }
  static void store(double* p, V v) { _mm256_store_pd(p, v); }
  static V add(V a, V b) { return _mm256_add_pd(a, b); }
  static V sub(V a, V b) { return _mm256_sub_pd(a, b); }
  static V mul(V a, V b) { return _mm256_mul_pd(a, b); }
  static V div(V a, V b) { return _mm256_div_pd(a, b); }
  static V fma(V a, V b, V c) { return _mm256_fmadd_pd(a, b, c); }
  static V clamp(V x, double lo, double hi) {
    return _mm256_max_pd(set(lo), _mm256_min_pd(set(hi), x));
  }
  static V round(V x) { return _mm256_round_pd(x, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC); }
  // 2^k for integral k in the normal range, from its exponent's bits.
  static V exp2_of_integer(V k) {
    const __m256i biased =
        _mm256_add_epi64(_mm256_cvtepi32_epi64(_mm256_cvtpd_epi32(k)), _mm256_set1_epi64x(1023));
    return _mm256_castsi256_pd(_mm256_slli_epi64(biased, 52));
  }
  // t, with x wherever x is NaN.
  static V nan_from(V t, V x) { return _mm256_blendv_pd(t, x, _mm256_cmp_pd(x, x, _CMP_UNORD_Q)); }
};

#ifdef EIGEN_VECTORIZE_AVX512
/// The same on 8 doubles (AVX-512F): the same operations lane by lane, so the same bits.
struct Avx512Doubles {
  using V = __m512d;
  static constexpr int kWidth = 8;
  static V set(double v) { return _mm512_set1_pd(v); }
  static V load(const double* p) { return _mm512_loadu_pd(p); }
  static void store(double* p, V v) { _mm512_store_pd(p, v); }
  static V add(V a, V b) { return _mm512_add_pd(a, b); }
  static V sub(V a, V b) { return _mm512_sub_pd(a, b); }
  static V mul(V a, V b) { return _mm512_mul_pd(a, b); }
  static V div(V a, V b) { return _mm512_div_pd(a, b); }
  static V fma(V a, V b, V c) { return _mm512_fmadd_pd(a, b, c); }
  static V clamp(V x, double lo, double hi) {
    return _mm512_max_pd(set(lo), _mm512_min_pd(set(hi), x));
  }
  static V round(V x) {
    return _mm512_roundscale_pd(x, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
  }
  static V exp2_of_integer(V k) {
    const __m512i biased =
        _mm512_add_epi64(_mm512_cvtepi32_epi64(_mm512_cvtpd_epi32(k)), _mm512_set1_epi64(1023));
    return _mm512_castsi512_pd(_mm512_slli_epi64(biased, 52));
  }
  static V nan_from(V t, V x) {
    return _mm512_mask_blend_pd(_mm512_cmp_pd_mask(x, x, _CMP_UNORD_Q), t, x);
  }
};
#endif

/// tanh of a packet of doubles: (E - 1) / (E + 1), E = e^{2x}, 2x clamped to [-40, 40] (beyond
/// it tanh is +-1 in double). e^y = 2^k e^r with k = round(y / ln 2) and r = y - k ln 2 in
/// [-ln2/2, ln2/2] (ln 2 in two parts, so that k ln 2 is exact), e^r by its Taylor series to r^12
/// in Estrin's scheme (the next term is below 2e-16), 2^k from its exponent's bits. 1.4x the
/// speed of Eigen's exp and a division (its exp divides too) on a Zen 3 with 4 lanes, at the same
/// absolute error (a few ulps of 1). A NaN stays NaN. Written once for both widths, so a machine
/// with AVX-512 and one with AVX2 alone give the same bits.
template <typename Isa>
typename Isa::V tanh_packet(typename Isa::V x) {
  using V = typename Isa::V;
  const auto c = [](double v) { return Isa::set(v); };
  const V y = Isa::clamp(Isa::add(x, x), -40.0, 40.0);
  const V k = Isa::round(Isa::mul(y, c(1.4426950408889634)));
  V r = Isa::fma(k, c(-0.693145751953125), y);
  r = Isa::fma(k, c(-1.4286068203094172321e-6), r);
  const V r2 = Isa::mul(r, r), r4 = Isa::mul(r2, r2), r8 = Isa::mul(r4, r4);
  const V p01 = Isa::add(r, c(1.0));
  const V p23 = Isa::fma(r, c(1.0 / 6), c(0.5));
  const V p45 = Isa::fma(r, c(1.0 / 120), c(1.0 / 24));
  const V p67 = Isa::fma(r, c(1.0 / 5040), c(1.0 / 720));
  const V p89 = Isa::fma(r, c(1.0 / 362880), c(1.0 / 40320));
  const V p1011 = Isa::fma(r, c(1.0 / 39916800), c(1.0 / 3628800));
  const V p03 = Isa::fma(r2, p23, p01), p47 = Isa::fma(r2, p67, p45);
  const V p811 = Isa::fma(r2, p1011, p89);
  const V p07 = Isa::fma(r4, p47, p03);
  const V p812 = Isa::fma(r4, c(1.0 / 479001600), p811);
  const V e = Isa::mul(Isa::fma(r8, p812, p07), Isa::exp2_of_integer(k));
  return Isa::nan_from(Isa::div(Isa::sub(e, c(1.0)), Isa::add(e, c(1.0))), x);
}

/// The widest packet this build has.
#ifdef EIGEN_VECTORIZE_AVX512
using DoublePacket = Avx512Doubles;
#else
using DoublePacket = Avx2Doubles;
#endif
#endif

/// dst = tanh(src) on contiguous arrays, dst aligned to 64 bytes and the size a multiple of
/// kLine (tanh_values passes whole lines). Float: Eigen's vectorised tanh. Double: Eigen calls
/// the scalar libm tanh, which dominated HNN training; with AVX2 or AVX-512, tanh_packet; else
/// 2 / (1 + e^-2x) - 1 on Eigen's vectorised exp (absolute error a few ulps of 1; saturates
/// correctly at +-1, e^-2x -> 0 or inf).
template <typename Dst, typename Src>
void tanh_formula(Dst&& dst, const Src& src) {
  using T = typename std::decay_t<Dst>::Scalar;
  if constexpr (std::is_same_v<T, float>) {
    dst = src.tanh();
  } else {
#ifdef HNN_SIMD_DOUBLE_TANH
    for (Eigen::Index i = 0; i < src.size(); i += DoublePacket::kWidth) {
      DoublePacket::store(dst.data() + i,
                          tanh_packet<DoublePacket>(DoublePacket::load(src.data() + i)));
    }
#else
    dst = T(2) / (T(1) + (T(-2) * src).exp()) - T(1);
#endif
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
