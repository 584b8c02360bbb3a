#pragma once
// The engine's worker threads: fused kernels and big ops split a batch into row blocks, one per
// thread. Workers are created once; between jobs they watch for the next one for 500 us, then
// sleep (futex waits), so jobs in quick succession cost no wake-up and an idle pool steals no
// shared machine's cores (Note [Brief spin] in parallel.cpp).

#include <Eigen/Core>
#include <type_traits>

namespace hnn::ad {

/// Threads the fused kernels may use (default: the hardware's, at most 8). n >= 1.
void set_num_threads(int n);
int num_threads();
/// The threads an op may split its work over here: num_threads(), or 1 inside a part of
/// parallel_for, whose nested calls run in turn on the part's thread (splitting there would only
/// add the pieces' partial sums). A step split by rows (nn/row_split.h) thus runs each block as
/// one thread would.
int available_threads();

/// A non-owning callable void(int): no allocation, unlike std::function.
class PartFn {
 public:
  // Refers to f, which must outlive the call (a lambda argument lives until the call returns).
  template <typename F>
  requires(!std::is_same_v<std::decay_t<F>, PartFn>) PartFn(F&& f)  // NOLINT: implicit by design
      : object_(const_cast<void*>(static_cast<const void*>(&f))),
        call_([](void* o, int i) { (*static_cast<std::remove_reference_t<F>*>(o))(i); }) {}
  void operator()(int i) const { call_(object_, i); }

 private:
  void* object_;
  void (*call_)(void*, int);
};

/// Calls part(i) for i in [0, parts) concurrently and returns when all have finished: the caller
/// and the workers claim parts as they get to them, so a worker the scheduler has not woken yet
/// delays nothing (Note [Claimed parts] in parallel.cpp). The first exception thrown by a part
/// (lowest i) is rethrown here. `parts` may exceed the threads: whoever finishes a part claims the
/// next. Nested calls, calls while another thread's job holds the workers, and jobs of more than
/// 65,535 parts run the same parts serially: the split (and so every result, bit for bit)
/// depends only on `parts`.
void parallel_for(int parts, PartFn part);

/// parallel_for with part i on the pool's thread i (the caller's is 0): each thread runs the same
/// part every time, so the buffers it keeps for that part (its tape, its scratch) keep their
/// shapes from call to call (Note [Pinned parts] in parallel.cpp). A part whose worker has not
/// started it by the time the caller finishes part 0 is run by the caller (stolen_parts() counts
/// them). For a few long parts; parts <= num_threads(). Nested and concurrent calls run serially,
/// as parallel_for's do.
void parallel_for_each_thread(int parts, PartFn part);
/// Parts of parallel_for_each_thread that the caller ran for a late worker, since the start.
long stolen_parts();

/// Row block i of `parts` equal blocks of `rows`: [begin, end).
struct RowBlock {
  Eigen::Index begin, end;
  Eigen::Index size() const { return end - begin; }
};
RowBlock row_block(Eigen::Index rows, int parts, int i);
/// Block i of `parts` nearly equal blocks of a flat array of n elements, each starting at a
/// multiple of 16 elements: Eigen then runs every block in the same SIMD packets as the whole
/// array (the only scalar tail is the array's own, in the last block), so an elementwise
/// expression gives the same bits at any split. (A split at any element put a packet's elements
/// on the scalar path, which contracts a * b + c into FMAs differently: the bits differed
/// between 1 and 3 threads on a Zen 3.)
RowBlock element_block(Eigen::Index n, int parts, int i);

/// Below this many elements an elementwise pass (an op, a sum of gradients) runs on the calling
/// thread: handing half to a worker would cost more than the work. Above it (an LNN's 512 x 128
/// or 512 x 600 layers, whose derivatives of any order are chains of elementwise ops between
/// GEMMs) the rows are split across the engine's threads as the GEMMs' are; left serial, these
/// ops were a quarter of a 2-thread LNN step at width 600 and most of it at width 128. (With
/// workers that spin briefly between jobs, Note [Brief spin], 2^15 measured best of 2^15, 2^16
/// and 2^18 on the LNN steps.)
inline constexpr Eigen::Index kParallelElements = Eigen::Index(1) << 15;

/// body(block) for the element blocks (element_block) of a flat array of n elements: one block on
/// the calling thread below kParallelElements, one per thread above. For elementwise work, whose
/// bits do not depend on the split.
template <typename Body>
void for_element_blocks(Eigen::Index n, const Body& body) {
  const int parts = n >= kParallelElements ? available_threads() : 1;
  if (parts == 1) return body(RowBlock{0, n});
  parallel_for(parts, [&](int i) { body(element_block(n, parts, i)); });
}

/// How many parts a batch of `rows` is worth splitting into: one per available thread, but at least
/// `min_rows` rows each (below that, waking a thread costs more than it saves).
int parts_for(Eigen::Index rows, Eigen::Index min_rows = 64);

}  // namespace hnn::ad
