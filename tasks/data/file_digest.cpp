#include "tasks/data/file_digest.h"

#include <fmt/format.h>
#include <openssl/evp.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <memory>

#include "tasks/error.h"

namespace hnn::tasks {

std::string file_sha256(const std::filesystem::path& file) {
  HNN_TASKS_CHECK(!std::filesystem::is_directory(file), "'{}' is a folder, not a file",
                  file.string());
  std::ifstream in(file, std::ios::binary);
  HNN_TASKS_CHECK(in.good(), "cannot read '{}': {}", file.string(), std::strerror(errno));
  const std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx(EVP_MD_CTX_new(),
                                                                    EVP_MD_CTX_free);
  HNN_TASKS_CHECK(ctx && EVP_DigestInit_ex(ctx.get(), EVP_sha256(), nullptr) == 1,
                  "cannot start a SHA-256 digest (OpenSSL)");
  std::array<char, 1 << 16> buffer;
  while (in) {
    in.read(buffer.data(), buffer.size());
    EVP_DigestUpdate(ctx.get(), buffer.data(), std::size_t(in.gcount()));
  }
  HNN_TASKS_CHECK(!in.bad(), "cannot read '{}': {}", file.string(), std::strerror(errno));
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest;
  unsigned int size = 0;
  EVP_DigestFinal_ex(ctx.get(), digest.data(), &size);
  std::string hex;
  for (unsigned int i = 0; i < size; ++i) hex += fmt::format("{:02x}", digest[i]);
  return hex;
}

}  // namespace hnn::tasks
