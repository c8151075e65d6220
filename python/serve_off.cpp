// Pipeline(serve=...) in a module built without the serving layer (-DMESHFLOW_SERVE=OFF or no
// Boost): a clear error instead of the viewer (python/serve.cpp has the real one).

#include "python/bindings.h"
#include "runtime/error.h"

namespace meshflow::python {

std::unique_ptr<LiveView> start_live_view(const py::object&, const py::object&, const py::object&) {
  throw Error("Pipeline", "serve",
              "a meshflow module built with the serving layer (Boost, Debian's libboost-dev)");
}

}  // namespace meshflow::python
