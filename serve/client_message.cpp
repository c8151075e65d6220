#include "serve/client_message.h"

#include <nlohmann/json.hpp>

namespace meshflow::serve {

bool valid_client_message(std::string_view text) {
  const nlohmann::json doc = nlohmann::json::parse(text.begin(), text.end(), nullptr,
                                                   /*allow_exceptions=*/false);
  if (!doc.is_object()) return false;
  const auto type = doc.find("type");
  return type != doc.end() && type->is_string() && (*type == "hello" || *type == "ping");
}

}  // namespace meshflow::serve
