#include "serve/client_message.h"

#include <nlohmann/json.hpp>

namespace meshflow::serve {

std::optional<ClientMessage> parse_client_message(std::string_view text) {
  const nlohmann::json doc = nlohmann::json::parse(text.begin(), text.end(), nullptr,
                                                   /*allow_exceptions=*/false);
  if (!doc.is_object()) return std::nullopt;
  const auto type = doc.find("type");
  if (type == doc.end() || !type->is_string()) return std::nullopt;
  if (*type == "hello") return ClientMessage{ClientMessage::Type::kHello, 0};
  if (*type == "ping") return ClientMessage{ClientMessage::Type::kPing, 0};
  if (*type != "map_ack") return std::nullopt;
  const auto round = doc.find("round");
  // Only a JSON integer >= 0 parses as unsigned (a fraction or exponent is a float).
  if (round == doc.end() || !round->is_number_unsigned()) return std::nullopt;
  const std::uint64_t n = round->get<std::uint64_t>();
  if (n == 0 || n > 0xffffffffull) return std::nullopt;
  return ClientMessage{ClientMessage::Type::kMapAck, static_cast<std::uint32_t>(n)};
}

bool valid_client_message(std::string_view text) { return parse_client_message(text).has_value(); }

}  // namespace meshflow::serve
