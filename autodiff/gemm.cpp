// The GEMM backend's one-time setup (gemm.h).

#include "autodiff/gemm.h"

namespace hnn::ad::detail {

void init_gemm() {
#ifdef HNN_HAVE_OPENBLAS
  // The engine splits batches over its own threads; OpenBLAS threads would oversubscribe.
  static const bool once = [] {
    openblas_set_num_threads(1);
    return true;
  }();
  (void)once;
#endif
}

}  // namespace hnn::ad::detail
