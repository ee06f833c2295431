#pragma once
// Checkpoints: what a plugin carries from one step to the next beyond the
// kernel's arrays (a law's history kept by the element, a contact
// handler's stuck points and search lists, ...), written after a step and
// read back into a plugin configured by the same job, so that a restarted
// run (`thermostamp run --restart`) continues bit for bit as the run
// would have without the stop.
//
// A plugin writes its values in an order of its own with put() and reads
// them back in the same order with get(); sizes travel with the arrays and
// are checked. Only trivially copyable values (numbers, plain structs).
// Values a plugin derives again from its configuration and the current
// state (factorisations, caches keyed on what they were formed for) need
// not be written, as long as deriving them again gives the same bits.
#include <cstdint>
#include <cstring>
#include <span>
#include <type_traits>
#include <vector>

namespace ts::sdk {

class StateWriter {
 public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const unsigned char*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  // An array: its length, then its values.
  template <class T>
  void put_array(std::span<const T> values) {
    static_assert(std::is_trivially_copyable_v<T>);
    put(static_cast<std::uint64_t>(values.size()));
    if (values.empty()) return;
    const auto* p = reinterpret_cast<const unsigned char*>(values.data());
    bytes_.insert(bytes_.end(), p, p + values.size() * sizeof(T));
  }
  template <class V>
  void put_vector(const V& v) {
    put_array(std::span<const typename V::value_type>(v.data(), v.size()));
  }
  // The calls a StateReader answers with the same names (io, io_array,
  // io_vector), so that a plugin may list its values once, in a function
  // template called with either.
  template <class T>
  bool io(const T& value) {
    put(value);
    return true;
  }
  template <class V>
  bool io_array(const V& v) {
    put_vector(v);
    return true;
  }
  template <class V>
  bool io_vector(const V& v) {
    put_vector(v);
    return true;
  }
  const std::vector<unsigned char>& bytes() const { return bytes_; }
  std::vector<unsigned char>& bytes() { return bytes_; }

 private:
  std::vector<unsigned char> bytes_;
};

// Reads what a StateWriter wrote. Every get() returns false (and reads
// nothing more) once a value runs past the end or an array's length does
// not fit; done() then says so too.
class StateReader {
 public:
  explicit StateReader(std::span<const unsigned char> bytes) : bytes_(bytes) {}
  template <class T>
  bool get(T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (!ok_ || bytes_.size() - pos_ < sizeof(T)) return ok_ = false;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return true;
  }
  // An array whose length the reader knows: it must match.
  template <class T>
  bool get_array(std::span<T> values) {
    std::uint64_t n = 0;
    if (!get(n) || n != values.size() || bytes_.size() - pos_ < n * sizeof(T)) return ok_ = false;
    if (n > 0) std::memcpy(values.data(), bytes_.data() + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
    return true;
  }
  // An array of any length, into a vector (resized).
  template <class V>
  bool get_vector(V& v) {
    std::uint64_t n = 0;
    using T = typename V::value_type;
    if (!get(n) || (bytes_.size() - pos_) / sizeof(T) < n) return ok_ = false;
    v.resize(n);
    if (n > 0) std::memcpy(v.data(), bytes_.data() + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
    return true;
  }
  // The names of StateWriter's: io reads a value, io_array an array into
  // a container of the length it has, io_vector one of any length.
  template <class T>
  bool io(T& value) {
    return get(value);
  }
  template <class V>
  bool io_array(V& v) {
    return get_array(std::span<typename V::value_type>(v.data(), v.size()));
  }
  template <class V>
  bool io_vector(V& v) {
    return get_vector(v);
  }
  bool ok() const { return ok_; }
  // Everything read, nothing left over.
  bool done() const { return ok_ && pos_ == bytes_.size(); }

 private:
  std::span<const unsigned char> bytes_;
  std::size_t pos_ = 0;
  bool ok_ = true;
};

}  // namespace ts::sdk
