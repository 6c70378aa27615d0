// SPDX-License-Identifier: MIT
// A plain OBJ read without assimp's scene: assimp's OBJ importer took 60 to
// 80 ms of oacmpctf3's 300 ms compile (7.8 MB, 99k triangles), in a child
// process whose mesh then crossed a pipe. This reader accepts only what it
// can read exactly as assimp does, and leaves everything else to assimp.
#include "import_obj.h"

#include <assimp/fast_atof.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <string>

namespace bspc {

namespace {

// Larger files go to assimp in its contained child, whose memory is
// capped: this reader holds about 2.5 times the file in this process.
constexpr off_t kMaxPlainObjBytes = off_t(1) << 30;

// The whole of a regular file of at most kMaxPlainObjBytes, followed by a
// '\0' (every scan stops at it); nothing for anything else. Opened as the
// import opens files: never waiting on a FIFO or device.
std::optional<std::string> readRegularFile(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  std::optional<std::string> text;
  struct stat info {};
  if (::fstat(fd, &info) == 0 && S_ISREG(info.st_mode) && info.st_size > 0 &&
      info.st_size <= kMaxPlainObjBytes) {
    std::string bytes(static_cast<std::size_t>(info.st_size) + 1, '\0');
    std::size_t done = 0;
    while (done + 1 < bytes.size()) {
      const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - 1 - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      done += static_cast<std::size_t>(n);
    }
    // A file that shrank while read, or failed, is left to assimp.
    if (done + 1 == bytes.size()) text = std::move(bytes);
  }
  ::close(fd);
  return text;
}

// What assimp's number parser throws here, instead of its own exception
// (whose constructor the shared library does not export), for a word it
// cannot read ("1e", say): the file is then left to assimp.
struct NotANumber {
  template <typename... Parts>
  explicit NotANumber(Parts&&...) {}
};

bool isDigit(char c) { return c >= '0' && c <= '9'; }
bool isBlank(char c) { return c == ' ' || c == '\t'; }

// The common form of an OBJ coordinate, [-+]digits[.digits], read with
// the arithmetic of assimp's parser (fast_atoreal_move, which took 106
// instructions a number): the integer part made a float; up to 15
// fraction digits as an integer, scaled by assimp's table of powers of
// ten in double, made a float and added; the sign last. Returns where the
// number ends, or nullptr for any other form (an exponent, no digit before
// the point, more than 19 integer digits), which assimp's parser reads.
// The tests hold the two equal bit for bit.
const char* decimal(const char* p, float& value) {
  const bool negative = *p == '-';
  if (negative || *p == '+') ++p;
  std::uint64_t whole = 0;
  const char* digits = p;
  for (; isDigit(*p); ++p) whole = 10 * whole + std::uint64_t(*p - '0');
  if (p == digits || p - digits > 19) return nullptr;
  float f = static_cast<float>(whole);
  if (*p == '.') {
    ++p;
    std::uint64_t fraction = 0;
    unsigned places = 0;
    for (; isDigit(*p) && places < 15; ++p, ++places)
      fraction = 10 * fraction + std::uint64_t(*p - '0');
    while (isDigit(*p)) ++p;  // beyond what a double holds: ignored, as assimp does
    if (places > 0)
      f += static_cast<float>(static_cast<double>(fraction) * Assimp::fast_atof_table[places]);
  }
  if (*p == 'e' || *p == 'E') return nullptr;
  value = negative ? -f : f;
  return p;
}

// Reads a plain OBJ a statement at a time, refusing (a reader returns
// false) what assimp might read otherwise. The text ends in a '\0' that
// stops every scan, so no scan checks for the end itself: a '\0' is the
// end only where `end` is.
class PlainObjReader {
 public:
  PlainObjReader(const char* begin, const char* end) : at_(begin), end_(end) {}

  bool done() const { return at_ == end_; }
  char first() const { return *at_; }
  void skip() { ++at_; }

  // Blanks that must be there, as between a statement and its values.
  bool skipSomeBlanks() {
    if (!isBlank(*at_)) return false;
    while (isBlank(*++at_)) {
    }
    return true;
  }

  // The end of a line: optional blanks, then "\n", "\r\n" or the file's
  // end (a lone '\r' may end a line in assimp, so is refused elsewhere).
  bool endLine() {
    while (isBlank(*at_)) ++at_;
    if (*at_ == '\r') ++at_;
    if (*at_ == '\n') {
      ++at_;
      return true;
    }
    return at_ == end_;
  }

  // A comment, to the end of its line. One holding a '\0', a lone '\r' or
  // a '\\' (assimp joins a line ending in one to the next) is refused.
  bool comment() {
    for (;; ++at_) {
      switch (*at_) {
        case '\n': ++at_; return true;
        case '\0': return at_ == end_;
        case '\\': return false;
        case '\r':
          if (at_[1] != '\n') return false;
          break;
        default: break;
      }
    }
  }

  // A vertex coordinate: a word assimp counts as a number (it starts with
  // a digit or a sign) and reads whole, as the float assimp reads.
  // Anything assimp's parser stops short in is refused.
  bool number(float& value) {
    if (!isDigit(*at_) && *at_ != '-' && *at_ != '+') return false;
    const char* after = decimal(at_, value);
    if (!after) {
      try {
        after = Assimp::fast_atoreal_move<float, NotANumber>(at_, value);
      } catch (const NotANumber&) {
        return false;
      }
    }
    if (!endsWord(after)) return false;
    at_ = after;
    return true;
  }

  // A vertex index as -?digits without a leading zero (assimp reads it
  // with atoi and steps over as many characters as the value has digits),
  // at most 9 digits, so it fits an int.
  bool index(std::int64_t& value) {
    const char* p = at_;
    const bool negative = *p == '-';
    if (negative) ++p;
    if (*p < '1' || *p > '9') return false;
    std::int64_t magnitude = 0;
    const char* digits = p;
    // Stops accumulating past 9 digits (the word is refused then) so a
    // long run of digits cannot overflow.
    for (; isDigit(*p); ++p)
      if (p - digits < 9) magnitude = 10 * magnitude + (*p - '0');
    if (p - digits > 9 || !endsWord(p)) return false;
    value = negative ? -magnitude : magnitude;
    at_ = p;
    return true;
  }

 private:
  bool endsWord(const char* p) const {
    return isBlank(*p) || *p == '\r' || *p == '\n' || p == end_;
  }

  const char* at_;
  const char* end_;
};

}  // namespace

std::optional<std::vector<std::array<float, 3>>> readPlainObjCorners(
    const std::filesystem::path& path) {
  const std::optional<std::string> text = readRegularFile(path);
  if (!text) return std::nullopt;
  PlainObjReader in(text->data(), text->data() + text->size() - 1);
  std::vector<std::array<float, 3>> positions;
  // Each corner's vertex, 0-based; checked against every vertex once all
  // are read, as assimp checks (a face may name a vertex defined after it).
  std::vector<std::uint32_t> corners;
  positions.reserve(text->size() / 32);
  corners.reserve(text->size() / 16);
  while (!in.done()) {
    switch (in.first()) {
      case '\n':
      case '\r':
        if (!in.endLine()) return std::nullopt;
        break;
      case '#':
        if (!in.comment()) return std::nullopt;
        break;
      case 'v': {
        in.skip();
        std::array<float, 3>& p = positions.emplace_back();
        for (float& c : p)
          if (!in.skipSomeBlanks() || !in.number(c)) return std::nullopt;
        if (!in.endLine()) return std::nullopt;
        break;
      }
      case 'f': {
        in.skip();
        for (int k = 0; k < 3; ++k) {
          std::int64_t i = 0;
          if (!in.skipSomeBlanks() || !in.index(i)) return std::nullopt;
          // Negative: counted back from the last vertex read so far.
          const std::int64_t resolved = i > 0 ? i - 1 : std::int64_t(positions.size()) + i;
          if (resolved < 0) return std::nullopt;
          corners.push_back(static_cast<std::uint32_t>(resolved));
        }
        if (!in.endLine()) return std::nullopt;  // a polygon, or more after the face
        break;
      }
      default: return std::nullopt;
    }
  }
  if (corners.empty()) return std::nullopt;
  std::vector<std::array<float, 3>> cornerPositions(corners.size());
  for (std::size_t k = 0; k < corners.size(); ++k) {
    if (corners[k] >= positions.size()) return std::nullopt;
    cornerPositions[k] = positions[corners[k]];
  }
  return cornerPositions;
}

}  // namespace bspc
