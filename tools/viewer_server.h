#pragma once
// The viewer's server for the CLI (built with the serving layer only): the page's fixed files,
// the server on the user's --serve options, and serving until Ctrl-C or --exit-after.

#include <cstddef>
#include <cstdio>
#include <memory>

#include "serve/server.h"
#include "tools/run_view.h"

namespace meshflow::cli {

/// Starts the server with the viewer page (web/ and Debian's libjs-three, read once) on
/// `options`' address, rate cap and viewer limit, cutting meshes into `chunk_bytes` messages.
/// Throws meshflow::Error for a bad address, one in use, or a missing page file.
std::unique_ptr<serve::Server> start_viewer_server(const ServeOptions& options,
                                                   std::size_t chunk_bytes = 64 * 1024);

/// Returns at Ctrl-C (SIGINT, SIGTERM) or after `exit_after` seconds (0: only at Ctrl-C), then
/// prints what `server` sent on `out`.
void serve_until_stopped(const serve::Server& server, double exit_after, std::FILE* out);

}  // namespace meshflow::cli
