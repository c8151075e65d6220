#pragma once
// Errors for bad data at a boundary (file, frame, user configuration).
// Programming errors inside the library use assert() instead.

#include <stdexcept>
#include <string>

namespace meshflow {

/// Bad input: names the source (usually a file path), where in it (line, field, element)
/// and what was expected. what() reads "SOURCE: LOCATION: PROBLEM" (LOCATION omitted if empty).
class Error : public std::runtime_error {
 public:
  /// `source`: the file or stage; `location`: the line, field or element (may be empty);
  /// `problem`: what was wrong and what was expected.
  Error(std::string source, std::string location, std::string problem);

  /// The file or stage the error is about.
  const std::string& source() const { return source_; }
  /// The line, field or element (may be empty).
  const std::string& location() const { return location_; }
  /// What was wrong and what was expected.
  const std::string& problem() const { return problem_; }

 private:
  std::string source_;
  std::string location_;
  std::string problem_;
};

}  // namespace meshflow
