// SHA-256 (OpenSSL EVP) of bytes given in pieces, as hex: the digests of recordings and inputs
// in RESULT.json, the database's provenance checks (sha256_file) and the CSV reader's digest
// while reading.
#pragma once
#include <cstddef>
#include <memory>
#include <string>

namespace calbench {

class Sha256 {
 public:
  Sha256();
  void update(const void* data, std::size_t n);
  std::string hex();  // finishes the digest; update() may not follow

 private:
  struct Free {
    void operator()(void* ctx) const;
  };
  std::unique_ptr<void, Free> ctx_;  // EVP_MD_CTX
};

}  // namespace calbench
