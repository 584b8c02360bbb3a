#pragma once
// A thread's floating-point mode, and denormals flushed to zero for a scope.
//
// Note [Denormals flushed]: late in a float training run, products of saturated tanh units'
// derivatives and small gradients fall below float's normal range (1.2e-38), and every
// operation on such a number takes a microcode assist: the spring's float step in
// hnn_train_step went from 1.5 ms to 3.6 ms on average after about 3,000 steps (4,000 steps:
// 13.6 s of wall time, 6.0 s with denormals flushed, the same final loss to the last bit). So the
// training loop (tasks/train/loop.cpp), which `hnn train`, `hnn.train` and `Model.fit` all run,
// flushes them (FTZ and DAZ) while it runs and restores the caller's mode after: a program or a
// Python session that links the library keeps its own mode outside training, as TensorFlow's
// ScopedFlushDenormal does for its ops. The engine's threads compute every part in the mode of
// the thread that asked for it (parallel.cpp), so where a part runs never changes its bits.

#if defined(__SSE3__)
#include <pmmintrin.h>
#endif

namespace hnn::ad {

/// A thread's floating-point mode: the control bits of MXCSR on x86 (rounding, flush-to-zero,
/// denormals-are-zero, exception masks), without its sticky exception flags, which the
/// computations set and which stay the thread's own; 0 on builds without SSE3, which leave the
/// mode alone.
using FloatMode = unsigned;
#if defined(__SSE3__)
inline constexpr unsigned kExceptionFlags = 0x3F;  // MXCSR bits 0-5: raised exceptions
#endif

inline FloatMode float_mode() {
#if defined(__SSE3__)
  return _mm_getcsr() & ~kExceptionFlags;
#else
  return 0;
#endif
}

inline void set_float_mode([[maybe_unused]] FloatMode mode) {
#if defined(__SSE3__)
  const unsigned csr = _mm_getcsr();
  if ((csr & ~kExceptionFlags) != mode) _mm_setcsr((csr & kExceptionFlags) | mode);
#endif
}

/// Denormal results and operands are read as zero on this thread until the scope ends, when the
/// mode before it comes back (Note [Denormals flushed]).
class FlushDenormals {
 public:
  FlushDenormals() {
#if defined(__SSE3__)
    set_float_mode(before_ | _MM_FLUSH_ZERO_ON | _MM_DENORMALS_ZERO_ON);
#endif
  }
  ~FlushDenormals() { set_float_mode(before_); }
  FlushDenormals(const FlushDenormals&) = delete;
  FlushDenormals& operator=(const FlushDenormals&) = delete;

 private:
  FloatMode before_ = float_mode();
};

}  // namespace hnn::ad
