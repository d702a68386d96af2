#include "bench/console/http_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <condition_variable>
#include <cstring>
#include <deque>
#include <functional>
#include <thread>

namespace calbench::console {
using Clock = std::chrono::steady_clock;

namespace {

// A thread per task (connection) up to `max` threads; a thread idle for 30 s ends. Beyond `max`,
// tasks wait for a thread. (httplib's ThreadPool has a fixed number of threads: 64 slow clients or
// live pages held them all.)
class GrowingQueue : public httplib::TaskQueue {
 public:
  explicit GrowingQueue(std::size_t max) : max_(max) {}
  void enqueue(std::function<void()> fn) override {
    std::unique_lock<std::mutex> l(m_);
    jobs_.push_back(std::move(fn));
    // idle_ counts threads waiting for a job, also those already woken for another one: a new thread
    // when there are more jobs waiting than that.
    if (jobs_.size() > idle_ && threads_ < max_) {
      ++threads_;
      std::thread([this] { work(); }).detach();
    }
    cv_.notify_one();
  }
  void shutdown() override {
    std::unique_lock<std::mutex> l(m_);
    stop_ = true;
    cv_.notify_all();
    done_.wait(l, [&] { return threads_ == 0; });
  }

 private:
  void work() {
    std::unique_lock<std::mutex> l(m_);
    for (;;) {
      ++idle_;
      const bool got = cv_.wait_for(l, std::chrono::seconds(30), [&] { return !jobs_.empty() || stop_; });
      --idle_;
      if (jobs_.empty() && (stop_ || !got)) break;
      auto fn = std::move(jobs_.front());
      jobs_.pop_front();
      l.unlock();
      fn();
      l.lock();
    }
    --threads_;
    done_.notify_all();
  }
  std::size_t max_, threads_ = 0, idle_ = 0;
  bool stop_ = false;
  std::mutex m_;
  std::condition_variable cv_, done_;
  std::deque<std::function<void()>> jobs_;
};

std::string address_of(const sockaddr_storage& a, int& port) {
  char b[INET6_ADDRSTRLEN] = "?";
  port = 0;
  if (a.ss_family == AF_INET) {
    const auto& v4 = reinterpret_cast<const sockaddr_in&>(a);
    inet_ntop(AF_INET, &v4.sin_addr, b, sizeof b);
    port = ntohs(v4.sin_port);
  } else if (a.ss_family == AF_INET6) {
    const auto& v6 = reinterpret_cast<const sockaddr_in6&>(a);
    inet_ntop(AF_INET6, &v6.sin6_addr, b, sizeof b);
    port = ntohs(v6.sin6_port);
  }
  return b;
}

constexpr int kMaxRequests = 100;  // per connection, then it is closed (the client opens another)

int ms_until(Clock::time_point t) {
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(t - Clock::now()).count();
  return ms <= 0 ? 0 : static_cast<int>(std::min<long long>(ms, 60000));
}

// Waits until the socket is readable/writable or `until`: true when it is.
bool wait_socket(int fd, short events, Clock::time_point until) {
  for (;;) {
    pollfd p{fd, events, 0};
    const int r = ::poll(&p, 1, ms_until(until));
    if (r > 0) return true;
    if (r == 0) return false;
    if (errno != EINTR) return false;
  }
}

}  // namespace

// A connection as httplib::Stream: non-blocking socket (and TLS session), every read bounded by the
// request's deadline and byte budget, every write by the write timeout.
class DeadlineStream : public httplib::Stream {
 public:
  DeadlineStream(int fd, SSL* ssl, const HttpLimits& lim) : fd_(fd), ssl_(ssl), lim_(lim) {
    sockaddr_storage a{};
    socklen_t n = sizeof a;
    if (getpeername(fd, reinterpret_cast<sockaddr*>(&a), &n) == 0) peer_ = address_of(a, peer_port_);
    n = sizeof a;
    if (getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n) == 0) local_ = address_of(a, local_port_);
  }
  const std::string& peer() const { return peer_; }
  // A new request: its deadline and budget start now.
  void begin_request(Clock::time_point deadline) {
    deadline_ = deadline;
    budget_ = lim_.request_bytes;
  }
  bool failed() const { return failed_; }
  bool buffered() const { return pos_ < len_ || (ssl_ && SSL_pending(ssl_) > 0); }
  bool wait_request(Clock::time_point until) { return buffered() || wait_socket(fd_, POLLIN, until); }

  bool is_readable() const override { return buffered() || wait_socket(fd_, POLLIN, deadline_); }
  bool is_writable() const override {
    if (!wait_socket(fd_, POLLOUT, Clock::now() + lim_.write_timeout)) return false;
    char c;  // the client closed its end: nothing more to write
    return !ssl_ ? ::recv(fd_, &c, 1, MSG_PEEK | MSG_DONTWAIT) != 0 : true;
  }
  ssize_t read(char* ptr, size_t size) override {
    if (pos_ == len_) {
      pos_ = len_ = 0;
      const ssize_t n = fill();
      if (n <= 0) {
        failed_ = true;
        return -1;
      }
      len_ = static_cast<std::size_t>(n);
    }
    std::size_t n = std::min(size, len_ - pos_);
    if (n > budget_) n = budget_;
    if (n == 0) {
      failed_ = true;  // over the request's byte budget
      return -1;
    }
    std::memcpy(ptr, buf_ + pos_, n);
    pos_ += n;
    budget_ -= n;
    return static_cast<ssize_t>(n);
  }
  ssize_t write(const char* ptr, size_t size) override {
    std::size_t done = 0;
    const auto until = Clock::now() + lim_.write_timeout;
    while (done < size) {
      const ssize_t n = io(const_cast<char*>(ptr) + done, size - done, true, until);
      if (n <= 0) return -1;
      done += static_cast<std::size_t>(n);
    }
    return static_cast<ssize_t>(size);
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override { ip = peer_, port = peer_port_; }
  void get_local_ip_and_port(std::string& ip, int& port) const override { ip = local_, port = local_port_; }
  socket_t socket() const override { return fd_; }

  // One TLS or plain read/write, waiting (poll) until `until`: bytes moved, or <= 0.
  ssize_t io(char* p, std::size_t n, bool out, Clock::time_point until) {
    for (;;) {
      short want = out ? POLLOUT : POLLIN;
      if (ssl_) {
        const int r = out ? SSL_write(ssl_, p, static_cast<int>(n)) : SSL_read(ssl_, p, static_cast<int>(n));
        if (r > 0) return r;
        const int e = SSL_get_error(ssl_, r);
        if (e == SSL_ERROR_WANT_READ) want = POLLIN;
        else if (e == SSL_ERROR_WANT_WRITE) want = POLLOUT;
        else return -1;
      } else {
        const ssize_t r = out ? ::send(fd_, p, n, MSG_NOSIGNAL) : ::recv(fd_, p, n, 0);
        if (r >= 0) return r;
        if (errno == EINTR) continue;
        if (errno != EAGAIN && errno != EWOULDBLOCK) return -1;
      }
      if (!wait_socket(fd_, want, until)) return -1;
    }
  }

 private:
  ssize_t fill() { return io(buf_, sizeof buf_, false, deadline_); }

  int fd_;
  SSL* ssl_;
  const HttpLimits& lim_;
  std::string peer_, local_;
  int peer_port_ = 0, local_port_ = 0;
  Clock::time_point deadline_{};
  std::size_t budget_ = 0;
  bool failed_ = false;
  char buf_[4096];
  std::size_t pos_ = 0, len_ = 0;
};

ConsoleHttpServer::ConsoleHttpServer(const HttpLimits& limits, SSL_CTX* tls) : lim_(limits), tls_(tls) {
  // Threads beyond the connection cap only take connections that are answered 503 at once.
  const std::size_t threads = lim_.max_connections + 16;
  new_task_queue = [threads] { return new GrowingQueue(threads); };
  set_keep_alive_max_count(kMaxRequests);  // what the Keep-Alive header announces
}

ConsoleHttpServer::~ConsoleHttpServer() {
  if (tls_) SSL_CTX_free(tls_);
}

bool ConsoleHttpServer::bind(const std::string& host, int port) {
  if (!bind_to_port(host, port)) return false;
  // httplib listened with its compiled-in backlog of 5: bursts of connections were reset.
  return ::listen(svr_sock_, lim_.backlog) == 0;
}

bool ConsoleHttpServer::admit(const std::string& address) {
  const std::lock_guard<std::mutex> l(m_);
  std::size_t& mine = per_address_[address];
  if (open_ >= lim_.max_connections || mine >= lim_.per_address) {
    if (mine == 0) per_address_.erase(address);
    return false;
  }
  ++open_;
  ++mine;
  return true;
}

void ConsoleHttpServer::leave(const std::string& address) {
  const std::lock_guard<std::mutex> l(m_);
  --open_;
  if (--per_address_[address] == 0) per_address_.erase(address);
}

void ConsoleHttpServer::serve_connection(DeadlineStream& strm, Clock::time_point accepted) {
  for (int n = 0; n < kMaxRequests; ++n) {
    const auto wait_until = n == 0 ? accepted + lim_.request_deadline : Clock::now() + lim_.keep_alive;
    if (!strm.wait_request(wait_until)) return;
    strm.begin_request(n == 0 ? accepted + lim_.request_deadline : Clock::now() + lim_.request_deadline);
    bool closed = false;
    const bool last = n + 1 == kMaxRequests || !is_running();
    if (!process_request(strm, last, closed, nullptr)) return;
    // A request cut off by its deadline or budget was answered (400) or not: either way, no more.
    if (closed || last || strm.failed()) return;
  }
}

bool ConsoleHttpServer::process_and_close_socket(socket_t sock) {
  const auto accepted = Clock::now();
  fcntl(sock, F_SETFL, fcntl(sock, F_GETFL) | O_NONBLOCK);
  SSL* ssl = nullptr;
  const std::string peer = DeadlineStream(sock, nullptr, lim_).peer();
  {
    if (!admit(peer)) {
      const std::string body = "too many connections (from your address): try again in a moment\n";
      const std::string busy = "HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain\r\nRetry-After: 5\r\n"
                               "Connection: close\r\nContent-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body;
      (void)::send(sock, busy.data(), busy.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      ::shutdown(sock, SHUT_RDWR);
      ::close(sock);
      return false;
    }
  }
  bool ok = true;
  if (tls_) {  // the handshake under the request deadline too
    ssl = SSL_new(tls_);
    ok = ssl && SSL_set_fd(ssl, sock) == 1;
    for (int r; ok && (r = SSL_accept(ssl)) != 1;) {
      const int e = SSL_get_error(ssl, r);
      ok = (e == SSL_ERROR_WANT_READ || e == SSL_ERROR_WANT_WRITE) &&
           wait_socket(sock, e == SSL_ERROR_WANT_READ ? POLLIN : POLLOUT, accepted + lim_.request_deadline);
    }
  }
  DeadlineStream strm(sock, ssl, lim_);
  if (ok) serve_connection(strm, accepted);
  leave(peer);
  if (ssl) {
    if (ok) SSL_shutdown(ssl);
    SSL_free(ssl);
  }
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
  return ok;
}

}  // namespace calbench::console
