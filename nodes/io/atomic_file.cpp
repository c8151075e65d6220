#include "nodes/io/atomic_file.h"

#include <cerrno>
#include <cstdio>
#include <filesystem>

#include "nodes/io/parse_util.h"
#include "runtime/error.h"

namespace meshflow::io {

AtomicOutputFile::AtomicOutputFile(std::string path)
    : path_(std::move(path)), temp_path_(path_ + ".tmp") {
  errno = 0;
  out_.open(temp_path_, std::ios::binary | std::ios::trunc);
  if (!out_) throw Error(path_, "", "cannot create output file: " + errno_text());
}

AtomicOutputFile::~AtomicOutputFile() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    std::filesystem::remove(temp_path_, ec);
  }
}

void AtomicOutputFile::commit() {
  errno = 0;
  out_.flush();
  if (!out_) throw Error(path_, "", "write failed: " + errno_text());
  out_.close();
  std::error_code ec;
  std::filesystem::rename(temp_path_, path_, ec);
  if (ec) throw Error(path_, "", "cannot rename temporary file: " + ec.message());
  committed_ = true;
}

}  // namespace meshflow::io
