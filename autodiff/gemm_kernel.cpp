// The fused kernels' own GEMM on AVX-512 machines (gemm.h, simd_gemm).
//
// Note [A GEMM without packing]: the MLP steps multiply row blocks of 100-400 rows by weights of
// a few hundred squared, a handful of times per layer, each call on its own engine thread.
// OpenBLAS copies ("packs") both operands into its own layout on every call, and at these
// shapes the copies cost about a fifth of its GEMM time (15.5% of the whole CHNN step). Here
// each call keeps a tile of C in registers (kRows rows of kVectors SIMD vectors: 28 of the 32
// registers) and runs down the shared dimension: one broadcast of an element of A and kVectors
// loads of a row of B feed kRows x kVectors fused multiply-adds. Both operands are read where
// they lie. A is read by element, so a transposed A costs nothing; B is read by rows, so only a
// transposed B needs a copy: a panel of its columns at a time, on the stack, small enough for
// the L1 cache (what OpenBLAS packs for every operand, packed here only where it must be).

#include <algorithm>
#include <array>
#include <utility>

#include "autodiff/gemm.h"

#ifdef __AVX512F__
#include <immintrin.h>
#endif

namespace hnn::ad::detail {

#ifdef __AVX512F__
namespace {

using Index = Eigen::Index;

template <typename T>
struct Lanes;

template <>
struct Lanes<float> {
  using V = __m512;
  using Mask = __mmask16;
  static constexpr int kWidth = 16;
  static V zero() { return _mm512_setzero_ps(); }
  static V broadcast(const float* p) { return _mm512_set1_ps(*p); }
  static V load(const float* p, Mask m) { return _mm512_maskz_loadu_ps(m, p); }
  static V load(const float* p) { return _mm512_loadu_ps(p); }
  static void store(float* p, V v, Mask m) { _mm512_mask_storeu_ps(p, m, v); }
  static void store(float* p, V v) { _mm512_storeu_ps(p, v); }
  static V fma(V a, V b, V c) { return _mm512_fmadd_ps(a, b, c); }
};

template <>
struct Lanes<double> {
  using V = __m512d;
  using Mask = __mmask8;
  static constexpr int kWidth = 8;
  static V zero() { return _mm512_setzero_pd(); }
  static V broadcast(const double* p) { return _mm512_set1_pd(*p); }
  static V load(const double* p, Mask m) { return _mm512_maskz_loadu_pd(m, p); }
  static V load(const double* p) { return _mm512_loadu_pd(p); }
  static void store(double* p, V v, Mask m) { _mm512_mask_storeu_pd(p, m, v); }
  static void store(double* p, V v) { _mm512_storeu_pd(p, v); }
  static V fma(V a, V b, V c) { return _mm512_fmadd_pd(a, b, c); }
};

// The tile: kRows x kVectors accumulators, 28 of AVX-512's 32 registers; the rest hold B's row
// and A's broadcast element. 14 x 2 ran 1.1-1.3x OpenBLAS's GEMM at 100 x 256 x 256 in float on
// an AVX-512 Xeon (the three orientations), where 6 x 4 (fewer loads, a wider panel of B than the
// L1 cache holds) ran 1.0-1.2x.
constexpr int kRows = 14;
constexpr int kVectors = 2;
// The shared dimension in blocks of this many, so that a panel of B (kDepth x kVectors vectors:
// 16 KiB) and a tile's rows of A stay in the L1 cache (32 KiB on a Zen 4). The CHNN step took
// 21.2 ms with 128, 22.7 with 256 and 24.3 with 64 (2 threads, one run each). In double, 256
// ran the spring's A B and A B^T 1.08x faster alone on the Xeon's 48 KiB L1 (autodiff_bench
// BM_Gemm) and its step 0.96-0.99x the time, 64 1.02-1.04x; at 256 a double panel alone fills a
// Zen 4's L1, so both types keep 128 until a Zen 4 can say.
constexpr Index kDepth = 128;

// Note [Where the kernel takes the product]: OpenBLAS's packing pays for itself on wide
// operands, where each packed panel serves many tiles, and its L2 blocking keeps them in cache;
// there the kernel lost (the LNN's 600-wide step 1.25x slower, the pixel model's 1,568 inputs
// 1.1x). A last panel that C only partly fills wastes lanes: the spring's 200 columns in float
// left 24 of a two-vector panel's 32 empty, and its step ran 1.03-1.09x slower; a last panel of
// one vector now takes a one-vector tile, which leaves 8 of 16 empty and ran that step 0.97x the
// time of OpenBLAS's, the rollout loss's 0.87x and the two-body's 0.91x (2 threads). Many rows
// lose too: a weight gradient over the pixel model's 1,568 inputs (C 1,568 x 200, A^T B over 100
// rows) ran 0.94x OpenBLAS's speed alone, the pixel step 1.05-1.08x slower, as each panel streams
// all of A again. So it takes products whose C and shared dimension are at most kWidest in every
// direction, with at most 1/16 of their vectors' lanes empty, and leaves the rest to OpenBLAS.
constexpr Index kWidest = 384;

template <typename T>
using Masks = std::array<typename Lanes<T>::Mask, kVectors>;
/// Columns of C per panel: kVectors vectors.
template <typename T>
constexpr Index kPanel = Index(Lanes<T>::kWidth) * kVectors;

/// The mask of a vector's first `count` lanes (count <= its width).
template <typename T>
typename Lanes<T>::Mask first_lanes(Index count) {
  return typename Lanes<T>::Mask((std::uint64_t(1) << count) - 1);
}

/// C's rows [0, R) and a panel of its columns (masks say which) += or = op(A)'s rows [0, R)
/// times the panel of B (rows of stride ldb), over `depth` terms. op(A)'s element (r, p) is
/// a[r * lda + p], or a[p * lda + r] when A comes transposed: strides the compiler knows, so that
/// a row of op(A) costs no register of its own. The loops over the tile are unrolled by pragma:
/// GCC's own heuristics unrolled them after it had placed the accumulators in memory, and every
/// step down the shared dimension stored all 28 of them. Only a last, partly filled panel reads
/// and writes through its masks (kMasked): a masked load takes a slot of the ports the FMAs
/// use, and full panels ran 1.03-1.07x faster without (the tile alone, in the L1 cache).
template <typename T, int R, int V, bool kTransposedA, bool kMasked>
void tile(Index depth, const T* a, Index lda, const T* b, Index ldb, T* c, Index ldc,
          const Masks<T>& m, bool accumulate) {
  const Index row_stride = kTransposedA ? 1 : lda, depth_stride = kTransposedA ? lda : 1;
  using L = Lanes<T>;
  const auto load = [&m](const T* p, int v) {
    if constexpr (kMasked) return L::load(p, m[std::size_t(v)]);
    return L::load(p);
  };
  const auto store = [&m](T* p, typename L::V x, int v) {
    if constexpr (kMasked) return L::store(p, x, m[std::size_t(v)]);
    return L::store(p, x);
  };
  typename L::V acc[R][V];
#pragma GCC unroll 16
  for (int r = 0; r < R; ++r) {
#pragma GCC unroll 16
    for (int v = 0; v < V; ++v) {
      acc[r][v] = accumulate ? load(c + r * ldc + v * L::kWidth, v) : L::zero();
    }
  }
  for (Index p = 0; p < depth; ++p) {
    typename L::V row[V];
#pragma GCC unroll 16
    for (int v = 0; v < V; ++v) row[v] = load(b + p * ldb + v * L::kWidth, v);
#pragma GCC unroll 16
    for (int r = 0; r < R; ++r) {
      const typename L::V element = L::broadcast(a + r * row_stride + p * depth_stride);
#pragma GCC unroll 16
      for (int v = 0; v < V; ++v) acc[r][v] = L::fma(element, row[v], acc[r][v]);
    }
  }
#pragma GCC unroll 16
  for (int r = 0; r < R; ++r) {
#pragma GCC unroll 16
    for (int v = 0; v < V; ++v) store(c + r * ldc + v * L::kWidth, acc[r][v], v);
  }
}

template <typename T>
using TileFn = void (*)(Index, const T*, Index, const T*, Index, T*, Index, const Masks<T>&, bool);

/// tile<T, R, V, ...> for R = 1..kRows, at index R - 1: the last rows of a block take a shorter
/// tile.
template <typename T, int V, bool kTransposedA, bool kMasked, std::size_t... R>
constexpr std::array<TileFn<T>, sizeof...(R)> tiles(std::index_sequence<R...>) {
  return {&tile<T, int(R) + 1, V, kTransposedA, kMasked>...};
}
template <typename T, int V, bool kTransposedA, bool kMasked>
constexpr auto kTiles = tiles<T, V, kTransposedA, kMasked>(std::make_index_sequence<kRows>());

template <typename T, int V, bool kMasked>
const std::array<TileFn<T>, kRows>& tiles_of(bool ta) {
  return ta ? kTiles<T, V, true, kMasked> : kTiles<T, V, false, kMasked>;
}

/// The tiles for a panel `width` columns wide: a last panel of one vector runs half the FMAs of
/// a two-vector one, and only a panel that C partly fills needs masks.
template <typename T>
const std::array<TileFn<T>, kRows>& tiles_for(Index width, bool ta) {
  constexpr Index w = Lanes<T>::kWidth;
  if (width > w)
    return width == kPanel<T> ? tiles_of<T, kVectors, false>(ta) : tiles_of<T, kVectors, true>(ta);
  return width == w ? tiles_of<T, 1, false>(ta) : tiles_of<T, 1, true>(ta);
}

/// The masks of a panel with `width` of its columns in C.
template <typename T>
Masks<T> panel_masks(Index width) {
  constexpr int w = Lanes<T>::kWidth;
  Masks<T> m{};
  for (int v = 0; v < kVectors; ++v) {
    m[std::size_t(v)] = first_lanes<T>(std::clamp<Index>(width - v * w, 0, w));
  }
  return m;
}

/// Where the kernel beats OpenBLAS (Note [Where the kernel takes the product]).
template <typename T>
bool suits_the_kernel(const GemmOperands<T>& g) {
  constexpr Index w = Lanes<T>::kWidth;
  const Index padded = (g.n + w - 1) / w * w;
  // (An empty product, k = 0, must still scale C by beta: BLAS does that.)
  return g.m > 0 && g.k > 0 && (g.beta == T(0) || g.beta == T(1)) &&
         std::max({g.m, g.n, g.k}) <= kWidest && 16 * (padded - g.n) <= g.n;
}

/// A panel of op(B) = B^T: packed[p * kPanel<T> + jj] = b[jj * ldb + p] for jj < width <= kPanel
/// and p < depth, in square blocks of kWidth transposed in registers (Eigen's ptranspose).
/// Element by element, that copy took a third of the time of the products it served: the CHNN
/// step spent 7.3% in simd_gemm's own code then, 3.3% now (perf).
template <typename T>
void pack_transposed(const T* b, Index ldb, Index width, Index depth, T* packed) {
  using L = Lanes<T>;
  constexpr int w = L::kWidth;
  // (GCC warns that a template argument drops __m512's alignment attribute; PacketBlock is
  // Eigen's own type for exactly these registers, as in its GEMM's packing.)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wignored-attributes"
  Eigen::internal::PacketBlock<typename L::V, w> block;
#pragma GCC diagnostic pop
  for (Index j0 = 0; j0 < width; j0 += w) {
    const Index rows = std::min<Index>(w, width - j0);
    for (Index p0 = 0; p0 < depth; p0 += w) {
      const Index cols = std::min<Index>(w, depth - p0);
      const auto mask = first_lanes<T>(cols);
      for (int r = 0; r < w; ++r) {
        block.packet[r] = r < rows ? L::load(b + (j0 + r) * ldb + p0, mask) : L::zero();
      }
      Eigen::internal::ptranspose(block);
      for (Index q = 0; q < cols; ++q) {
        L::store(packed + (p0 + q) * kPanel<T> + j0, block.packet[q]);
      }
    }
  }
}

}  // namespace

template <typename T>
bool simd_gemm(const GemmOperands<T>& g) {
  if (!suits_the_kernel(g)) return false;
  // B^T's panel, when B comes transposed: kDepth x kPanel on the stack (16 KiB).
  alignas(64) T packed[kDepth * kPanel<T>];
  const Index row_stride = g.ta ? 1 : g.lda, depth_stride = g.ta ? g.lda : 1;
  for (Index k0 = 0; k0 < g.k; k0 += kDepth) {
    const Index depth = std::min(kDepth, g.k - k0);
    const bool accumulate = k0 > 0 || g.beta == T(1);
    for (Index j = 0; j < g.n; j += kPanel<T>) {
      const Index width = std::min(kPanel<T>, g.n - j);
      const Masks<T> masks = panel_masks<T>(width);
      const auto& tiles = tiles_for<T>(width, g.ta);
      const T* b = g.b + k0 * g.ldb + j;
      Index ldb = g.ldb;
      if (g.tb) {
        pack_transposed(g.b + j * g.ldb + k0, g.ldb, width, depth, packed);
        b = packed;
        ldb = kPanel<T>;
      }
      // The rows in tiles of equal height, within one: 100 rows as 4 x 13 and 4 x 12, not
      // 7 x 14 and a tile of 2, whose 4 accumulators would wait on its loads.
      const Index count = (g.m + kRows - 1) / kRows, height = g.m / count, taller = g.m % count;
      for (Index t = 0, i = 0; t < count; ++t) {
        const Index rows = height + (t < taller ? 1 : 0);
        tiles[std::size_t(rows - 1)](depth, g.a + i * row_stride + k0 * depth_stride, g.lda, b, ldb,
                                     g.c + i * g.ldc + j, g.ldc, masks, accumulate);
        i += rows;
      }
    }
  }
  return true;
}
#else
template <typename T>
bool simd_gemm(const GemmOperands<T>&) {
  return false;
}
#endif

template bool simd_gemm(const GemmOperands<float>&);
template bool simd_gemm(const GemmOperands<double>&);

}  // namespace hnn::ad::detail
