#pragma once
// Output files that appear complete or not at all.

#include <fstream>
#include <string>

namespace meshflow::io {

/// Writes to "PATH.tmp" and renames it to PATH on commit(); if destroyed without commit()
/// (an exception during writing), the temporary file is removed and PATH is left untouched.
/// Throws meshflow::Error when the file cannot be created or written.
class AtomicOutputFile {
 public:
  explicit AtomicOutputFile(std::string path);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  std::ofstream& stream() { return out_; }
  void commit();

 private:
  std::string path_;
  std::string temp_path_;
  std::ofstream out_;
  bool committed_ = false;
};

}  // namespace meshflow::io
