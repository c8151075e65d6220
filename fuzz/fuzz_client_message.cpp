// libFuzzer target: the server's parser of a browser's message (serve/client_message.h) on any
// bytes: it must answer without crashing, throwing or reading out of bounds, an acknowledgement
// always names a round in [1, 2^32 - 1], and the yes/no check agrees with the parser.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "serve/client_message.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto message = meshflow::serve::parse_client_message(text);
  if (message.has_value() != meshflow::serve::valid_client_message(text)) std::abort();
  if (message && message->type == meshflow::serve::ClientMessage::Type::kMapAck &&
      message->round == 0)
    std::abort();
  return 0;
}
