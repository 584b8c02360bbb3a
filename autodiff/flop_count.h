#pragma once
// The floating-point operations of the engine's matrix products, counted for benchmarks that
// report a step as a fraction of the machine's FMA peak (bench/compare's hnn_train_step).

#include <cstdint>

namespace hnn::ad {

/// Counts 2mnk for every GEMM the engine runs, on any thread, while it lives. Off otherwise:
/// then each product pays one relaxed load. One counter at a time.
class GemmFlopCounter {
 public:
  GemmFlopCounter();
  ~GemmFlopCounter();
  GemmFlopCounter(const GemmFlopCounter&) = delete;
  GemmFlopCounter& operator=(const GemmFlopCounter&) = delete;
  /// The GEMM flops since construction.
  std::uint64_t flops() const;
};

}  // namespace hnn::ad
