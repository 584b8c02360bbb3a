#pragma once
// Sketch-and-precondition for ridge's problem min |A c - B|² + mu² |c|² (Rokhlin & Tygert 2008;
// Blendenpik, Avron, Maymounkov & Toledo 2010; LSRN, Meng, Saunders & Mahoney 2014): the QR of a
// sketch S A with a few times more rows than unknowns is a preconditioner under which LSQR on the
// whole problem converges in a few dozen iterations, at the sketch's QR cost instead of A's.
// Damping is what makes it work for sampled features: without it, R's near-dependent columns
// (half of a SWIM layer's lie within 1e-13 of the others' span) make R^-1 unbounded
// (docs/sampled.md, "The sketch solver").

#include <cstdint>

#include "nn/sampled/systems.h"

namespace hnn::nn::sampled {

/// Sketch rows per unknown: the embedding's distortion, and so LSQR's rate, improves with more;
/// its QR costs more (docs/sampled.md measures 2 against 3 and 4).
inline constexpr double kSketchRowsPerUnknown = 2;
/// Where mu |R^-1| stays below this, the preconditioner is R itself instead of the triangle of
/// [R; mu I], whose merge costs as much as one of the reduction's (0.55 s at width 3000): the
/// damping rows then add at most this much to the preconditioned singular values' spread.
inline constexpr double kNegligibleDamping = 0.1;
/// The sketch's seed for a fit's: a stream of its own, so that the sketch draws nothing from the
/// sampler's.
constexpr std::uint64_t sketch_seed(std::uint64_t fit_seed) {
  return fit_seed ^ 0x736b65746368ULL;  // "sketch"
}

/// Ridge's problem on one system, by LSQR preconditioned with the sketch's triangle.
class SketchedRidge {
 public:
  /// Sketches the system to kSketchRowsPerUnknown times its unknowns (no sketch when it has no
  /// more rows than that: the preconditioner is then exact) and reduces it to a triangle.
  SketchedRidge(const LinearSystem& system, std::uint64_t seed);

  struct Solution {
    ColMat c;
    int iterations = 0;
    std::size_t bytes = 0;  // the solve's own matrices
  };
  /// mu = rcond times A's largest singular value (largest()): the sketch's ridge solution,
  /// improved by LSQR on the whole damped problem until Paige & Saunders' test 2 passes at
  /// `tolerance` or after max_iterations.
  Solution solve(double rcond, double tolerance, int max_iterations) const;

  /// A's largest singular value, mu's scale: a few power steps on A^T A from the sketch's top
  /// right singular vector.
  double largest() const { return largest_; }
  /// Bytes of the sketch's triangle and right-hand side.
  std::size_t bytes() const;

 private:
  const LinearSystem& system_;
  ColMat r_, b_;  // the sketched problem's triangle (unknowns square) and its targets
  double largest_ = 0;
  double inverse_norm_ = 0;  // |R^-1|, from below (power steps)
};

}  // namespace hnn::nn::sampled
