#pragma once
// FNV-1a 64: the state hash every service reports with its ack. Cheap, stable across
// platforms and processes, so two runs can be compared frame by frame.
#include <cstdint>
#include <cstring>
#include <string_view>
#include <type_traits>

namespace lockstep {

class Fnv1a64 {
 public:
  static constexpr uint64_t kOffset = 14695981039346656037ull;
  static constexpr uint64_t kPrime = 1099511628211ull;

  Fnv1a64& Bytes(const void* data, size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) {
      value_ = (value_ ^ p[i]) * kPrime;
    }
    return *this;
  }
  // Arithmetic values hash by their bytes; -0.0 and 0.0 differ on purpose (bit-exact replay).
  template <class T>
    requires std::is_arithmetic_v<T> || std::is_enum_v<T>
  Fnv1a64& Add(T v) {
    return Bytes(&v, sizeof v);
  }
  Fnv1a64& Add(std::string_view s) {
    Add<uint64_t>(s.size());
    return Bytes(s.data(), s.size());
  }
  uint64_t value() const { return value_; }

 private:
  uint64_t value_ = kOffset;
};

inline uint64_t HashString(std::string_view s) {
  return Fnv1a64().Bytes(s.data(), s.size()).value();
}

}  // namespace lockstep
