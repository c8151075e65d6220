#include "runtime/error.h"

#include <utility>

namespace meshflow {
namespace {
std::string compose(const std::string& source, const std::string& location,
                    const std::string& problem) {
  std::string out = source;
  if (!location.empty()) out += ": " + location;
  return out + ": " + problem;
}
}  // namespace

Error::Error(std::string source, std::string location, std::string problem)
    : std::runtime_error(compose(source, location, problem)),
      source_(std::move(source)),
      location_(std::move(location)),
      problem_(std::move(problem)) {}

}  // namespace meshflow
