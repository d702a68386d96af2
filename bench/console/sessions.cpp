#include "bench/console/sessions.hpp"

#include <sodium.h>

#include <cstring>
#include <stdexcept>

namespace calbench::console {

std::string random_token() {
  static const bool ok = sodium_init() >= 0;
  if (!ok) throw std::runtime_error("libsodium could not be initialised");
  unsigned char b[32];
  randombytes_buf(b, sizeof b);
  char hex[65];
  sodium_bin2hex(hex, sizeof hex, b, sizeof b);
  return hex;
}

bool same_token(const std::string& a, const std::string& b) {
  return a.size() == b.size() && !a.empty() && sodium_memcmp(a.data(), b.data(), a.size()) == 0;
}

std::string Sessions::add(std::shared_ptr<Session> s) {
  const std::string token = random_token();
  s->csrf = random_token();
  s->created = s->last = Clock::now();
  const std::lock_guard<std::mutex> l(m_);
  by_token_[token] = std::move(s);
  return token;
}

std::shared_ptr<Session> Sessions::find(const std::string& token, bool touch) {
  const std::lock_guard<std::mutex> l(m_);
  const auto it = by_token_.find(token);
  if (it == by_token_.end()) return nullptr;
  const auto now = Clock::now();
  if (now - it->second->last > idle_ || now - it->second->created > kLifetime) {
    by_token_.erase(it);  // expired: its store (and connection) closes with the last request using it
    return nullptr;
  }
  if (touch) it->second->last = now;
  return it->second;
}

void Sessions::remove(const std::string& token) {
  const std::lock_guard<std::mutex> l(m_);
  by_token_.erase(token);
}

int Sessions::remove_login(const std::string& login) {
  const std::lock_guard<std::mutex> l(m_);
  int n = 0;
  for (auto it = by_token_.begin(); it != by_token_.end();) {
    if (it->second->login == login) {
      it = by_token_.erase(it);
      ++n;
    } else {
      ++it;
    }
  }
  return n;
}

Secret::Secret(std::string_view s) : n_(s.size()) {
  if (sodium_init() < 0) throw std::runtime_error("libsodium could not be initialised");
  p_ = static_cast<char*>(sodium_malloc(n_ ? n_ : 1));
  if (!p_) throw std::runtime_error("no locked memory for a session's password (sodium_malloc)");
  if (n_) std::memcpy(p_, s.data(), n_);
  sodium_mprotect_readonly(p_);
}

Secret::~Secret() {
  if (p_) sodium_free(p_);
}

}  // namespace calbench::console
