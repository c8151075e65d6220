#pragma once
// What a browser may send the server (serve/server.h): a small JSON object {"type": "hello"} or
// {"type": "ping"}. Anything else closes its connection. The parser is fuzzed
// (fuzz/fuzz_client_message.cpp).

#include <string_view>

namespace meshflow::serve {

/// Whether `text` is a message of the protocol: a JSON object whose "type" is "hello" or
/// "ping" (other fields are ignored). Never throws. O(size).
bool valid_client_message(std::string_view text);

}  // namespace meshflow::serve
