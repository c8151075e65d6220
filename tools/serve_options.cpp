#include <string>
#include <type_traits>

#include "tools/model_check.h"
#include "tools/run_view.h"

namespace meshflow::cli {

void add_serve_options(CLI::App* cmd, ServeOptions& o, const char* address_default) {
  std::vector<CLI::Option*> others;
  CLI::Option* serve = nullptr;
  for (const options::ServeOptionSpec& spec : options::serve_option_specs()) {
    const std::string name = spec.name;
    const std::string help =
        name != "serve" ? spec.help
        : address_default != nullptr
            ? "Where to serve the page: [HOST:]PORT (HOST 127.0.0.1 "
              "unless given; port 0: any free port; the URL is printed)"
            : std::string(spec.help) + ". The files written are the same with and without it";
    CLI::Option* option = std::visit(
        [&](auto member) {
          return cmd->add_option("--" + name, o.*member, help)
              ->check(model_check<ServeOptions>(spec, member));
        },
        spec.field);
    if (name == "serve")
      serve = option;
    else
      others.push_back(option);
  }
  if (address_default != nullptr) {
    o.address = address_default;
    serve->default_str(address_default);
  } else {
    for (CLI::Option* option : others) option->needs(serve);
  }
}

}  // namespace meshflow::cli
