#pragma once
// What a browser may send the server (serve/server.h): a small JSON object {"type": "hello"},
// {"type": "ping"} or {"type": "map_ack", "round": N} (the viewer has applied and drawn the
// map round N the server closed with {"type":"map_round","round":N}). Anything else closes its
// connection. The parser is fuzzed (fuzz/fuzz_client_message.cpp).

#include <cstdint>
#include <optional>
#include <string_view>

namespace meshflow::serve {

/// A message of the protocol, parsed.
struct ClientMessage {
  enum class Type { kHello, kPing, kMapAck } type = Type::kHello;
  std::uint32_t round = 0;  ///< kMapAck: the round acknowledged (1 .. 2^32 - 1); else 0
};

/// `text` parsed as a message of the protocol: a JSON object whose "type" is "hello" or "ping"
/// (other fields ignored), or "map_ack" with "round" an integer in [1, 2^32 - 1] (written
/// without fraction or exponent). std::nullopt for anything else. Never throws. O(size).
std::optional<ClientMessage> parse_client_message(std::string_view text);

/// Whether parse_client_message() accepts `text`. Never throws. O(size).
bool valid_client_message(std::string_view text);

}  // namespace meshflow::serve
