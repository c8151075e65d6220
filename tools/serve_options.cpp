#include "tools/run_view.h"

namespace meshflow::cli {

void add_serve_options(CLI::App* cmd, ServeOptions& o, const char* address_default) {
  CLI::Option* serve =
      cmd->add_option("--serve", o.address,
                      address_default != nullptr
                          ? "Where to serve the page: [HOST:]PORT (HOST 127.0.0.1 unless given; "
                            "port 0: any free port; the URL is printed)"
                          : "Show the run in a browser: serve the viewer page at [HOST:]PORT "
                            "(HOST 127.0.0.1 unless given; port 0: any free port; the URL is "
                            "printed). The files written are the same with and without it");
  if (address_default != nullptr) o.address = address_default;
  CLI::Option* options[] = {
      cmd->add_option("--exit-after", o.exit_after,
                      "Stop serving this many seconds after the result is ready (0: at Ctrl-C)")
          ->check(CLI::NonNegativeNumber),
      cmd->add_option("--serve-rate", o.rate_mbit,
                      "Cap each viewer's bandwidth, Mbit/s (0: none): how a narrow link feels")
          ->check(CLI::NonNegativeNumber),
      cmd->add_option("--max-viewers", o.max_viewers, "Browsers connected at once")
          ->check(CLI::Range(std::size_t{1}, std::size_t{256}))};
  if (address_default == nullptr)
    for (CLI::Option* option : options) option->needs(serve);
}

}  // namespace meshflow::cli
