#pragma once
// The byte stream of the render state (render_state.h): a snapshot a replacement render
// process restores, or, in hashing mode, the FNV-1a 64 of those same bytes (the service's
// state hash), so that the hash covers exactly what a snapshot restores. Values go by
// their bytes: the snapshot is for a process of the same build on the same kind of machine,
// as the other services' snapshots.
#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "lockstep/render/types.h"

namespace lockstep::render {

class StateOut {
 public:
  enum class Mode { kBytes, kHash };
  explicit StateOut(Mode mode = Mode::kBytes) : mode_(mode) {}

  void Bytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    if (mode_ == Mode::kBytes) {
      bytes_.insert(bytes_.end(), p, p + size);
      return;
    }
    for (std::size_t i = 0; i < size; ++i) hash_ = (hash_ ^ p[i]) * 1099511628211ull;
  }
  template <class T>
    requires std::is_arithmetic_v<T> || std::is_enum_v<T>
  StateOut& Put(T v) {
    Bytes(&v, sizeof v);
    return *this;
  }
  StateOut& Put(const std::string& s) {
    Put<std::uint64_t>(s.size());
    Bytes(s.data(), s.size());
    return *this;
  }
  StateOut& Put(const Vec3& v) { return Put(v.x()).Put(v.y()).Put(v.z()); }
  StateOut& Put(const Quat& q) { return Put(q.w()).Put(q.x()).Put(q.y()).Put(q.z()); }
  StateOut& Put(const Pose& p) { return Put(p.position).Put(p.orientation); }
  template <class T>
  StateOut& Put(const std::optional<T>& v) {
    Put<std::uint8_t>(v.has_value());
    if (v) Put(*v);
    return *this;
  }
  StateOut& Put(const std::map<std::string, std::string>& m) {
    Put<std::uint64_t>(m.size());
    for (const auto& [k, v] : m) Put(k).Put(v);
    return *this;
  }
  template <class T>
    requires std::is_arithmetic_v<T>
  StateOut& Put(const std::vector<T>& v) {
    Put<std::uint64_t>(v.size());
    Bytes(v.data(), v.size() * sizeof(T));
    return *this;
  }

  std::vector<std::uint8_t>& bytes() { return bytes_; }
  std::uint64_t hash() const { return hash_; }

 private:
  Mode mode_;
  std::vector<std::uint8_t> bytes_;
  std::uint64_t hash_ = 14695981039346656037ull;
};

// Reads what StateOut wrote; throws std::invalid_argument when the bytes end early or a
// count is larger than the bytes left could hold.
class StateIn {
 public:
  explicit StateIn(const std::vector<std::uint8_t>& bytes) : bytes_(bytes) {}

  void Bytes(void* out, std::size_t size) {
    if (size > bytes_.size() - at_) throw std::invalid_argument("render snapshot: truncated");
    std::memcpy(out, bytes_.data() + at_, size);
    at_ += size;
  }
  template <class T>
    requires std::is_arithmetic_v<T> || std::is_enum_v<T>
  StateIn& Get(T& v) {
    Bytes(&v, sizeof v);
    return *this;
  }
  // A count of items of at least `min_size` bytes each.
  std::uint64_t Count(std::size_t min_size) {
    std::uint64_t n = 0;
    Get(n);
    if (min_size > 0 && n > (bytes_.size() - at_) / min_size) throw std::invalid_argument("render snapshot: a count past its end");
    return n;
  }
  StateIn& Get(std::string& s) {
    s.resize(Count(1));
    Bytes(s.data(), s.size());
    return *this;
  }
  StateIn& Get(Vec3& v) {
    double x = 0, y = 0, z = 0;
    Get(x).Get(y).Get(z);
    v = Vec3(x, y, z);
    return *this;
  }
  StateIn& Get(Quat& q) {
    double w = 0, x = 0, y = 0, z = 0;
    Get(w).Get(x).Get(y).Get(z);
    q = Quat(w, x, y, z);
    return *this;
  }
  StateIn& Get(Pose& p) { return Get(p.position).Get(p.orientation); }
  template <class T>
  StateIn& Get(std::optional<T>& v) {
    std::uint8_t has = 0;
    Get(has);
    v.reset();
    if (has) Get(v.emplace());
    return *this;
  }
  StateIn& Get(std::map<std::string, std::string>& m) {
    m.clear();
    for (std::uint64_t n = Count(16); n > 0; --n) {
      std::string k, v;
      Get(k).Get(v);
      m[k] = std::move(v);
    }
    return *this;
  }
  template <class T>
    requires std::is_arithmetic_v<T>
  StateIn& Get(std::vector<T>& v) {
    v.resize(Count(sizeof(T)));
    Bytes(v.data(), v.size() * sizeof(T));
    return *this;
  }
  bool done() const { return at_ == bytes_.size(); }

 private:
  const std::vector<std::uint8_t>& bytes_;
  std::size_t at_ = 0;
};

}  // namespace lockstep::render
