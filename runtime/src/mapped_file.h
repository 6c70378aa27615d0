// SPDX-License-Identifier: MIT
// Read-only memory mapping of a whole file: POSIX mmap, or on Windows a
// file mapping view (CreateFileMapping, MapViewOfFile). Private to the runtime.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <span>
#include <string>

namespace bspf::detail {

class MappedFile {
 public:
  /// Maps `path`; on failure returns null and sets `error` to the reason.
  static std::shared_ptr<MappedFile> open(const std::filesystem::path& path, std::string& error);

  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile();

  std::span<const std::byte> bytes() const { return {data_, size_}; }

 private:
  MappedFile(const std::byte* data, std::size_t size) : data_(data), size_(size) {}
  const std::byte* data_;
  std::size_t size_;
#ifdef _WIN32
  // The file's handle, open (refusing writers) while mapped. On POSIX the
  // mapping alone keeps the file.
  void* file_ = nullptr;
#endif
};

}  // namespace bspf::detail
