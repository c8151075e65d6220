#pragma once
// Serving until the user stops it: the CLI's end of `meshflow view` and of runs with --serve.

#include <cstdio>

#include "serve/server.h"

namespace meshflow::cli {

/// Returns at Ctrl-C (SIGINT, SIGTERM) or after `exit_after` seconds (0: only at Ctrl-C), then
/// prints what `server` sent on `out`. Installs signal handlers; call from the main thread.
void serve_until_stopped(const serve::Server& server, double exit_after, std::FILE* out);

}  // namespace meshflow::cli
