// libFuzzer target: the server's check of a browser's message (serve/client_message.h) on any
// bytes: it must answer without crashing, throwing or reading out of bounds.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "serve/client_message.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  meshflow::serve::valid_client_message(
      std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
