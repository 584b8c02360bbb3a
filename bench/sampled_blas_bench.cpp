// The dense kernels of the sampled fit's qr solver at the protocols' shapes, alone: their
// FLOP rates against the FMA peak (roofline_bench's BM_FmaPeak) tell how much of the fit's
// solve is kernel speed and how much is the algorithm (docs/sampled.md).
//   sampled_blas_bench --rows 20000 --width 5000 --threads 2
// prints one JSON line per kernel: seconds and GFLOP/s, FLOPs counted from the shapes.

#include <fmt/format.h>

#include <chrono>
#include <string>

#include "autodiff/parallel.h"
#include "nn/sampled/blas.h"

namespace sampled = hnn::nn::sampled;
using sampled::ColMat;

namespace {

std::string arg(int argc, char** argv, const std::string& name, const std::string& fallback) {
  for (int i = 1; i + 1 < argc; ++i) {
    if (argv[i] == "--" + name) return argv[i + 1];
  }
  return fallback;
}

template <typename F>
void timed(const char* kernel, double flops, F&& run) {
  const auto start = std::chrono::steady_clock::now();
  run();
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  fmt::print("{{\"kernel\": \"{}\", \"seconds\": {:.3f}, \"gflops\": {:.1f}}}\n", kernel, s,
             flops / s * 1e-9);
}

}  // namespace

int main(int argc, char** argv) {
  const long n = std::stol(arg(argc, argv, "rows", "20000"));
  const long w = std::stol(arg(argc, argv, "width", "5000"));
  hnn::ad::set_num_threads(std::stoi(arg(argc, argv, "threads", "2")));
  const sampled::BlasThreads threads;
  const double dn = double(n), dw = double(w);
  ColMat d = ColMat::Random(n, w), g(w, w), c(w, w);
  timed("dsyrk", dn * dw * dw, [&] { sampled::blas_gram(d.data(), n, w, n, g, 0); });
  const ColMat sq = ColMat::Random(w, w);
  timed("dgemm", 2 * dw * dw * dw, [&] { sampled::blas_gemm(sq, false, sq, false, c); });
  ColMat b = ColMat::Random(n, 4);
  ColMat r;
  timed("dgeqrt+dgemqrt", 2 * dn * dw * dw - 2 * dw * dw * dw / 3,
        [&] { r = sampled::qr_apply(d, b); });
  ColMat t = r, top = b.topRows(w), bottom = b.topRows(w);
  timed("dtpqrt+dtpmqrt", 2 * dw * dw * dw / 3,
        [&] { sampled::qr_merge_triangle(r, t, top, bottom); });
  // dgelsd on the merged w x w triangle: bidiagonalisation 8/3 w^3, then the SVD's solve.
  timed("dgelsd", 8 * dw * dw * dw / 3, [&] { sampled::lstsq_svd(r, top, 1e-13); });
  return 0;
}
