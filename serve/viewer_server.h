#pragma once
// The viewer's server for the front ends (`meshflow view`, --serve, meshflow.serve): the page's
// fixed files, the server on the option model's serving options (options/serve_options.h), and a
// finished mesh encoded and published the way `meshflow view` shows it.

#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "nodes/compress/compressed_mesh.h"
#include "options/serve_options.h"
#include "runtime/triangle_mesh.h"
#include "serve/server.h"

namespace meshflow::serve {

/// The folder the viewer page is read from: $MESHFLOW_WEB_DIR when set, else the build's web/
/// output when it holds index.html (a build tree), else the installed copy
/// (<prefix>/share/meshflow/web). Thread-safe.
std::string viewer_page_folder();

/// Starts the server with the viewer page (viewer_page_folder() and Debian's libjs-three, read
/// once) on
/// `options`' address (validated by the option model first), rate cap and viewer limit, cutting
/// meshes into `chunk_bytes` messages; `extra` resources (e.g. "/mesh.mfc") are served beside
/// the page. Throws meshflow::Error for a bad address ("--serve"), one that cannot be bound
/// (naming it), or a missing page file.
std::unique_ptr<Server> start_viewer_server(const options::ServeOptions& options,
                                            std::size_t chunk_bytes = 64 * 1024,
                                            std::map<std::string, StaticResource> extra = {});

/// The codec settings a finished mesh is shown with (`meshflow view`, meshflow.serve): a base
/// mesh of 2 % of the triangles, 1024 vertex splits per packet (the finest step the page shows).
compress::CompressConfig view_compress_config();

/// A finished mesh ready for the page: its progressive .mfc image, the same mesh single-rate
/// (what follows the base on a fast link: Server::publish_mesh()) and the panel's figures.
struct ViewImage {
  std::vector<unsigned char> mfc;          ///< progressive .mfc image (base mesh first)
  std::vector<unsigned char> single_rate;  ///< single-rate .mfc image of the same mesh
  compress::CompressedMeshInfo info;
  std::size_t base_bytes = 0;  ///< bytes of the base mesh when encoded here (0: taken as given)
  double read_s = 0.0, encode_s = 0.0;
};

/// `path` (a mesh read_mesh() reads, or a .mfc file) as a progressive image: a progressive
/// .mfc is taken as it is (and decoded to encode its single-rate image), a single-rate one
/// decoded and re-encoded progressively (a picture from the first bytes), a mesh encoded with
/// `config`, both ways. Throws meshflow::Error naming the file for one that
/// cannot be read or has no triangles.
ViewImage view_image_of_file(const std::string& path, const compress::CompressConfig& config);

/// `mesh` (with triangles) as a progressive and a single-rate image encoded with `config`
/// (positions plus config.origin_offset, world coordinates). Throws meshflow::Error for a mesh
/// without triangles.
ViewImage view_image_of_mesh(const TriangleMesh& mesh, const compress::CompressConfig& config,
                             const std::string& name);

/// Publishes `image` on `server` as `meshflow view` does: the mesh, the panel's stats (`source`
/// e.g. "meshflow view", `file` the name shown), then the end. Does not wait for the network.
void publish_view(Server& server, const ViewImage& image, const std::string& source,
                  const std::string& file);

}  // namespace meshflow::serve
