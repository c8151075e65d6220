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
  Error(std::string source, std::string location, std::string problem);

  const std::string& source() const { return source_; }
  const std::string& location() const { return location_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string source_;
  std::string location_;
  std::string problem_;
};

}  // namespace meshflow
