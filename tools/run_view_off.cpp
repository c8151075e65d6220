// start_run_view() of a meshflow built without the serving layer (-DMESHFLOW_SERVE=OFF, or no
// Boost): --serve fails with a message instead of being an unknown option.

#include "runtime/error.h"
#include "tools/run_view.h"

namespace meshflow::cli {

std::unique_ptr<RunView> start_run_view(const ServeOptions& options, const std::string&) {
  if (!options.enabled()) return nullptr;
  throw Error("--serve", "",
              "a meshflow built with the serving layer (Boost.Beast: Debian's libboost-dev, "
              "-DMESHFLOW_SERVE=ON)");
}

}  // namespace meshflow::cli
