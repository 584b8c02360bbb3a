// Under OpenBLAS's OpenMP build, which LD_LIBRARY_PATH can swap in for the pthreads build the
// engine links (bench/compare's tuned environment does), the engine's workers must start no
// OpenMP teams of their own for their GEMMs (Note [One BLAS thread per engine thread] in
// autodiff/gemm.cpp). ctest runs this once more with that build and OMP_NUM_THREADS=2
// (tests/CMakeLists.txt: autodiff.BlasThreadsUnderOpenMp); elsewhere it is skipped.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "autodiff/autodiff.h"

namespace ad = hnn::ad;

namespace {

bool loaded(const std::string& library) {
  std::ifstream maps("/proc/self/maps");
  const std::string text((std::istreambuf_iterator<char>(maps)), std::istreambuf_iterator<char>());
  return text.find(library) != std::string::npos;
}

long threads_of_this_process() {
  const std::filesystem::directory_iterator tasks("/proc/self/task");
  return long(std::distance(begin(tasks), end(tasks)));
}

TEST(BlasThreads, TheEnginesGemmsStartNoThreadsOfTheirOwn) {
  if (!loaded("openblas-openmp")) GTEST_SKIP() << "runs under OpenBLAS's OpenMP build only";
  ad::set_num_threads(2);
  const ad::Var<double> a = ad::Var<double>::constant(ad::Matrix<double>::Random(512, 256));
  const ad::Var<double> w = ad::Var<double>::constant(ad::Matrix<double>::Random(256, 256));
  for (int i = 0; i < 50; ++i) {  // split in two row blocks: the worker runs some of them
    ad::TapeScope scope;
    ad::matmul(a, w);
  }
  EXPECT_EQ(threads_of_this_process(), 2) << "the caller and one engine worker, nothing else";
}

}  // namespace
