// libFuzzer harness: the measured-data table readers (CSV, .npy, .npz, Lipson text).

#include "fuzz/fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static hnn::fuzz::MemoryFile file;
  file.set(data, size);
  hnn::fuzz::table_input(file.path());
  return 0;
}
