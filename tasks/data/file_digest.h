#pragma once
// The SHA-256 of a file's bytes (OpenSSL's libcrypto): how a run recognises its data file after
// a move, and refuses another file in its place. The same hex digits as `sha256sum FILE`.

#include <filesystem>
#include <string>

namespace hnn::tasks {

/// 64 lowercase hex digits; throws Error naming the file when it cannot be read.
std::string file_sha256(const std::filesystem::path& file);

}  // namespace hnn::tasks
