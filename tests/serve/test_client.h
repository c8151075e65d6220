#pragma once
// What the serving layer's tests share: a test mesh, a WebSocket client with bounded waits, and a
// server configuration with a page.

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "runtime/triangle_mesh.h"
#include "serve/server.h"

namespace meshflow::serve::testing {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using error_code = boost::system::error_code;
using namespace std::chrono_literals;

/// An n x n grid of vertices on a wavy sheet, two triangles per square; `roughness` adds hashed
/// noise to the heights (meshes that compress less).
inline TriangleMesh wavy_grid(std::uint32_t n, float roughness = 0.0f) {
  TriangleMesh mesh;
  for (std::uint32_t y = 0; y < n; ++y)
    for (std::uint32_t x = 0; x < n; ++x) {
      const float fx = static_cast<float>(x) / static_cast<float>(n - 1);
      const float fy = static_cast<float>(y) / static_cast<float>(n - 1);
      const std::uint32_t hash = (x * 73856093u) ^ (y * 19349663u) * 2654435761u;
      const float noise = roughness * static_cast<float>(hash % 1000u) / 1000.0f;
      mesh.vertices.emplace_back(fx, fy, 0.1f * std::sin(7.0f * fx) * std::cos(5.0f * fy) + noise);
    }
  for (std::uint32_t y = 0; y + 1 < n; ++y)
    for (std::uint32_t x = 0; x + 1 < n; ++x) {
      const std::uint32_t a = y * n + x, b = a + 1, c = a + n, d = c + 1;
      mesh.triangles.push_back({a, b, d});
      mesh.triangles.push_back({a, d, c});
    }
  return mesh;
}

/// A WebSocket client on its own io_context; every operation waits at most `timeout`. Like the
/// page, it acknowledges each map round it reads ({"type":"map_round"}: serve/server.h) unless
/// made with `acknowledge` false.
class Client {
 public:
  explicit Client(std::size_t receive_buffer = 0, bool acknowledge = true)
      : receive_buffer_(receive_buffer), acknowledge_(acknowledge) {}

  error_code connect(std::uint16_t port, const std::string& target = "/ws") {
    error_code result;
    bool done = false;
    auto& socket = beast::get_lowest_layer(ws_).socket();
    socket.open(tcp::v4());
    if (receive_buffer_ > 0)
      socket.set_option(asio::socket_base::receive_buffer_size(static_cast<int>(receive_buffer_)));
    beast::get_lowest_layer(ws_).async_connect(
        tcp::endpoint(asio::ip::make_address("127.0.0.1"), port), [&](error_code ec) {
          if (ec) {
            result = ec;
            done = true;
            return;
          }
          ws_.async_handshake("127.0.0.1", target, [&](error_code ec2) {
            result = ec2;
            done = true;
          });
        });
    return wait(done, result);
  }

  error_code read(std::string& message, bool& binary) {
    error_code result;
    bool done = false;
    buffer_.consume(buffer_.size());
    ws_.async_read(buffer_, [&](error_code ec, std::size_t) {
      result = ec;
      done = true;
    });
    wait(done, result);
    message = beast::buffers_to_string(buffer_.data());
    binary = ws_.got_binary();
    if (!result && !binary && acknowledge_) {
      const nlohmann::json m = nlohmann::json::parse(message, nullptr, false);
      if (m.is_object() && m.value("type", "") == "map_round")
        return write(R"({"type":"map_ack","round":)" + std::to_string(m["round"].get<int>()) + "}");
    }
    return result;
  }

  error_code write(const std::string& message, bool binary = false) {
    error_code result;
    bool done = false;
    ws_.binary(binary);
    ws_.async_write(asio::buffer(message), [&](error_code ec, std::size_t) {
      result = ec;
      done = true;
    });
    return wait(done, result);
  }

  /// Reads until the connection ends (the error that ended it) or `timeout` passes
  /// (asio::error::timed_out).
  error_code read_until_closed() {
    for (;;) {
      std::string message;
      bool binary = false;
      const error_code ec = read(message, binary);
      if (ec) return ec;
    }
  }

  websocket::close_reason reason() const { return ws_.reason(); }

 private:
  error_code wait(bool& done, error_code& result) {
    ioc_.restart();
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (!done && std::chrono::steady_clock::now() < deadline) ioc_.run_one_for(20ms);
    if (!done) {
      beast::get_lowest_layer(ws_).socket().cancel();
      while (!done) ioc_.run_one_for(20ms);
      return asio::error::timed_out;
    }
    return result;
  }

  std::size_t receive_buffer_;
  bool acknowledge_;
  asio::io_context ioc_;
  websocket::stream<beast::tcp_stream> ws_{ioc_};
  beast::flat_buffer buffer_;
};

inline ServerConfig config_with_page() {
  ServerConfig config;
  config.resources["/"] = {"text/html", std::make_shared<const std::string>("<p>page</p>")};
  return config;
}

}  // namespace meshflow::serve::testing
