// libFuzzer harness: the parameter-file reader (read_parameter_file_info, load_parameters).

#include "fuzz/fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static hnn::fuzz::MemoryFile file;
  file.set(data, size);
  hnn::fuzz::parameters_input(file.path());
  return 0;
}
