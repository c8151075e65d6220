#pragma once
// Output files that appear complete or not at all.

#include <ostream>
#include <streambuf>
#include <string>
#include <vector>

namespace meshflow::io {

/// Writes to "PATH.tmp" and renames it to PATH on commit(); if destroyed without commit()
/// (an exception during writing), the temporary file is removed and PATH is left untouched. A
/// process killed while writing leaves at most "PATH.tmp" (never a partial PATH); the next write
/// of PATH replaces it. Throws meshflow::Error naming PATH and the system's reason (errno text,
/// e.g. "No space left on device") when the file cannot be created, written or renamed, or when
/// PATH is a directory.
/// Creates and removes PATH's temporary file, so that an output that cannot be written (a
/// directory, a missing or read-only directory, a full file system without a free inode) is an
/// error before a long computation, with the same message AtomicOutputFile would give.
void check_output_writable(const std::string& path);

class AtomicOutputFile {
 public:
  /// Opens `path`.tmp for writing. Throws meshflow::Error naming the file and the system's reason.
  explicit AtomicOutputFile(std::string path);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  /// The stream to write the file's content to (binary; buffered).
  std::ostream& stream() { return stream_; }
  /// Flushes, closes and renames the temporary file to the final path (atomically). Throws
  /// meshflow::Error on a failed write or rename, removing the temporary file.
  void commit();

 private:
  // A stream buffer over a POSIX file descriptor that keeps the errno of a failed write, which
  // std::ofstream loses.
  class FdBuffer : public std::streambuf {
   public:
    explicit FdBuffer(int fd);
    int error() const { return error_; }  ///< errno of the first failed write, 0 if none

   protected:
    int_type overflow(int_type c) override;
    int sync() override;
    std::streamsize xsputn(const char* s, std::streamsize n) override;

   private:
    bool drain();  // writes the buffered bytes; false (and error_ set) on failure
    int fd_;
    int error_ = 0;
    std::vector<char> buffer_;
  };

  std::string path_;
  std::string temp_path_;
  int fd_ = -1;
  FdBuffer buffer_;
  std::ostream stream_;
  bool committed_ = false;
};

}  // namespace meshflow::io
