// The console's HTTP(S) connection handling (issue 54 items 10 and 12), around cpp-httplib 0.11.
//
// Why a subclass of httplib::Server: Debian's compiled libcpp-httplib fixes its limits at build time
// (listen backlog 5, a per-read timeout only, no limit on the number of header lines, a fixed thread
// pool), and its server loop is not otherwise replaceable. What we keep from it is what it does
// well: request parsing, routing and response writing (the protected process_request()). What we
// replace is the private virtual process_and_close_socket() — the per-connection loop — with our own:
//  * a Stream with a deadline for a whole request (line, headers and body: `request_deadline`) and a
//    byte budget, so a client that sends a header line every few seconds is cut off, not served;
//  * connections counted in all and per client address (over the cap: 503 and closed at once);
//  * a task queue that starts a thread per connection up to the cap (and lets idle ones end), so
//    slow clients and open live-page streams do not starve the pages;
//  * TLS done here with OpenSSL (SSL_accept under the same deadline), since httplib::SSLServer's
//    own loop is the one being replaced: one loop, plain or TLS;
//  * the listen backlog raised to `backlog` (listen() again on the bound socket).
#pragma once
#include <openssl/ssl.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <map>
#include <mutex>
#include <string>

#include <httplib.h>

namespace calbench::console {

struct HttpLimits {
  std::size_t max_connections = 512;  // open connections in all (--max-connections)
  std::size_t per_address = 128;      // open connections from one client address
  std::chrono::seconds request_deadline{10};  // to receive a request's line, headers and body
  std::chrono::seconds keep_alive{5};         // an idle keep-alive connection is closed after this
  std::chrono::seconds write_timeout{10};     // one write may wait this long for the client
  std::size_t request_bytes = 96 * 1024;      // line + headers + body of one request
  int backlog = 1024;                         // listen backlog (the kernel caps it at net.core.somaxconn)
};

class ConsoleHttpServer : public httplib::Server {
 public:
  // `tls`: a server context (owned from here on), or null for plain HTTP.
  ConsoleHttpServer(const HttpLimits& limits, SSL_CTX* tls);
  ~ConsoleHttpServer() override;
  // bind_to_port, then the backlog raised. False when the address cannot be bound.
  bool bind(const std::string& host, int port);
  bool tls() const { return tls_ != nullptr; }

 private:
  bool process_and_close_socket(socket_t sock) override;
  bool admit(const std::string& address);
  void leave(const std::string& address);
  void serve_connection(class DeadlineStream& strm, std::chrono::steady_clock::time_point accepted);

  HttpLimits lim_;
  SSL_CTX* tls_;
  std::mutex m_;
  std::size_t open_ = 0;
  std::map<std::string, std::size_t> per_address_;
};

}  // namespace calbench::console
