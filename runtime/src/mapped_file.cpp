// SPDX-License-Identifier: MIT
#include "mapped_file.h"

#ifdef _WIN32
#ifndef WIN32_LEAN_AND_MEAN
#define WIN32_LEAN_AND_MEAN
#endif
#ifndef NOMINMAX
#define NOMINMAX
#endif
#include <windows.h>

#include <cstdint>
#include <limits>
#else
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#endif

namespace bspf::detail {

namespace {
// An empty file cannot be mapped; this stands in for its zero bytes.
alignas(8) const std::byte kNoBytes[8] = {};
}  // namespace

#ifdef _WIN32

namespace {

// The system's text for a Win32 error code, on one line.
std::string systemMessage(DWORD code) {
  char* text = nullptr;
  const DWORD length = ::FormatMessageA(
      FORMAT_MESSAGE_ALLOCATE_BUFFER | FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS,
      nullptr, code, 0, reinterpret_cast<char*>(&text), 0, nullptr);
  std::string message = length != 0 && text != nullptr ? std::string(text, length) : "";
  if (text != nullptr) ::LocalFree(text);
  while (!message.empty() && (message.back() == '\n' || message.back() == '\r' ||
                              message.back() == ' ' || message.back() == '.'))
    message.pop_back();
  if (message.empty()) message = "system error " + std::to_string(code);
  return message;
}

// Closes a handle when it goes out of scope.
struct HandleGuard {
  HANDLE handle;
  ~HandleGuard() {
    if (handle != nullptr && handle != INVALID_HANDLE_VALUE) ::CloseHandle(handle);
  }
};

}  // namespace

std::shared_ptr<MappedFile> MappedFile::open(const std::filesystem::path& path,
                                             std::string& error) {
  // The path's native form is UTF-16 here: any Unicode name opens. Backup
  // semantics let a directory open too, so it is refused below by type, as on
  // POSIX, not with "access denied". Others may read the file meanwhile, but
  // not write it: the handle stays open as long as the mapping (see the
  // destructor), so the level cannot change under a World. They may delete
  // or rename it, as on POSIX.
  const HANDLE file = ::CreateFileW(path.c_str(), GENERIC_READ, FILE_SHARE_READ | FILE_SHARE_DELETE,
                                    nullptr, OPEN_EXISTING, FILE_FLAG_BACKUP_SEMANTICS, nullptr);
  if (file == INVALID_HANDLE_VALUE) {
    error = systemMessage(::GetLastError());
    return nullptr;
  }
  HandleGuard fileGuard{file};
  // A console, printer port, pipe or socket is not FILE_TYPE_DISK.
  BY_HANDLE_FILE_INFORMATION info{};
  if (::GetFileType(file) != FILE_TYPE_DISK || !::GetFileInformationByHandle(file, &info) ||
      (info.dwFileAttributes & FILE_ATTRIBUTE_DIRECTORY) != 0) {
    error = "not a regular file";
    return nullptr;
  }
  const std::uint64_t size64 = (std::uint64_t(info.nFileSizeHigh) << 32) | info.nFileSizeLow;
  if (size64 > std::numeric_limits<std::size_t>::max()) {
    error = "too large to map";
    return nullptr;
  }
  const auto size = static_cast<std::size_t>(size64);
  if (size == 0) return std::shared_ptr<MappedFile>(new MappedFile(kNoBytes, 0));
  const HANDLE mapping = ::CreateFileMappingW(file, nullptr, PAGE_READONLY, 0, 0, nullptr);
  if (mapping == nullptr) {
    error = systemMessage(::GetLastError());
    return nullptr;
  }
  HandleGuard mappingGuard{mapping};  // the view keeps the mapping alive
  const void* data = ::MapViewOfFile(mapping, FILE_MAP_READ, 0, 0, 0);
  if (data == nullptr) {
    error = systemMessage(::GetLastError());
    return nullptr;
  }
  std::shared_ptr<MappedFile> mapped(new MappedFile(static_cast<const std::byte*>(data), size));
  mapped->file_ = file;
  fileGuard.handle = nullptr;  // now the MappedFile's
  return mapped;
}

MappedFile::~MappedFile() {
  if (size_ != 0) ::UnmapViewOfFile(data_);
  if (file_ != nullptr) ::CloseHandle(file_);
}

#else

std::shared_ptr<MappedFile> MappedFile::open(const std::filesystem::path& path,
                                             std::string& error) {
  // Non-blocking: opening a FIFO to read would otherwise wait for a writer
  // (forever, for a game loading a level). The type check below then
  // refuses it; a regular file ignores the flag.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    error = std::strerror(errno);
    return nullptr;
  }
  struct stat info {};
  if (::fstat(fd, &info) != 0) {
    error = std::strerror(errno);
    ::close(fd);
    return nullptr;
  }
  if (!S_ISREG(info.st_mode)) {
    error = "not a regular file";
    ::close(fd);
    return nullptr;
  }
  const auto size = static_cast<std::size_t>(info.st_size);
  if (size == 0) {
    ::close(fd);
    return std::shared_ptr<MappedFile>(new MappedFile(kNoBytes, 0));
  }
  void* data = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
  const int mapErrno = errno;
  ::close(fd);  // the mapping keeps the file alive
  if (data == MAP_FAILED) {
    error = std::strerror(mapErrno);
    return nullptr;
  }
  return std::shared_ptr<MappedFile>(new MappedFile(static_cast<const std::byte*>(data), size));
}

MappedFile::~MappedFile() {
  if (size_ != 0) ::munmap(const_cast<std::byte*>(data_), size_);
}

#endif

}  // namespace bspf::detail
