#include "bench/console/sessions.hpp"

#include <sodium.h>

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

std::string Sessions::locked(const std::string& login) {
  const std::lock_guard<std::mutex> l(m_);
  const auto it = failures_.find(login);
  if (it == failures_.end() || it->second.count < kMaxFailures) return {};
  const auto left = std::chrono::duration_cast<std::chrono::seconds>(it->second.until - Clock::now()).count();
  if (left <= 0) {
    failures_.erase(it);
    return {};
  }
  return "login '" + login + "' is locked after " + std::to_string(kMaxFailures) +
         " wrong passwords in a row; try again in " + std::to_string((left + 59) / 60) + " min";
}

void Sessions::failed(const std::string& login) {
  const std::lock_guard<std::mutex> l(m_);
  if (failures_.size() > 100000) failures_.clear();  // bounded memory under a flood of invented logins
  Failures& f = failures_[login];
  if (++f.count >= kMaxFailures) f.until = Clock::now() + kLockout;
}

void Sessions::succeeded(const std::string& login) {
  const std::lock_guard<std::mutex> l(m_);
  failures_.erase(login);
}

}  // namespace calbench::console
