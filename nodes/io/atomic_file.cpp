#include "nodes/io/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "runtime/error.h"

namespace meshflow::io {
namespace {

constexpr std::size_t kBufferBytes = 1 << 16;

// Opens `temp_path` for writing (created or truncated, 0666 less the umask); throws naming
// `path` when `path` is a directory or the file cannot be created.
int open_temp(const std::string& path, const std::string& temp_path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw Error(path, "", "cannot write the output: it is a directory");
  const int fd = ::open(temp_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0)
    throw Error(path, "", std::string("cannot create output file: ") + std::strerror(errno));
  return fd;
}

}  // namespace

void check_output_writable(const std::string& path) {
  const AtomicOutputFile probe(path);  // removed uncommitted
}

AtomicOutputFile::FdBuffer::FdBuffer(int fd) : fd_(fd), buffer_(kBufferBytes) {
  setp(buffer_.data(), buffer_.data() + buffer_.size());
}

bool AtomicOutputFile::FdBuffer::drain() {
  const char* p = pbase();
  while (p < pptr() && error_ == 0) {
    const ssize_t n = ::write(fd_, p, static_cast<std::size_t>(pptr() - p));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error_ = n < 0 ? errno : EIO;
      break;
    }
    p += n;
  }
  setp(buffer_.data(), buffer_.data() + buffer_.size());
  return error_ == 0;
}

AtomicOutputFile::FdBuffer::int_type AtomicOutputFile::FdBuffer::overflow(int_type c) {
  if (!drain()) return traits_type::eof();
  if (!traits_type::eq_int_type(c, traits_type::eof())) {
    *pptr() = traits_type::to_char_type(c);
    pbump(1);
  }
  return traits_type::not_eof(c);
}

int AtomicOutputFile::FdBuffer::sync() { return drain() ? 0 : -1; }

std::streamsize AtomicOutputFile::FdBuffer::xsputn(const char* s, std::streamsize n) {
  std::streamsize done = 0;
  while (done < n) {
    if (pptr() == epptr() && !drain()) return done;
    const std::streamsize room = epptr() - pptr();
    const std::streamsize chunk = std::min(room, n - done);
    std::memcpy(pptr(), s + done, static_cast<std::size_t>(chunk));
    pbump(static_cast<int>(chunk));
    done += chunk;
  }
  return done;
}

AtomicOutputFile::AtomicOutputFile(std::string path)
    : path_(std::move(path)),
      temp_path_(path_ + ".tmp"),
      fd_(open_temp(path_, temp_path_)),
      buffer_(fd_),
      stream_(&buffer_) {}

AtomicOutputFile::~AtomicOutputFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(temp_path_, ec);
  }
}

void AtomicOutputFile::commit() {
  stream_.flush();
  const auto fail = [&](int error) {
    throw Error(path_, "", std::string("write failed: ") + std::strerror(error != 0 ? error : EIO));
  };
  if (buffer_.error() != 0 || !stream_) fail(buffer_.error());
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail(errno);
  std::error_code ec;
  std::filesystem::rename(temp_path_, path_, ec);
  if (ec) throw Error(path_, "", "cannot rename temporary file: " + ec.message());
  committed_ = true;
}

}  // namespace meshflow::io
