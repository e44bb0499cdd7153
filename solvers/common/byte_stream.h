// Little binary writer and reader for saved states: fixed-width values in the machine's byte
// order (every supported target is little-endian; the header records it), vectors as a count
// followed by their elements. A truncated or foreign buffer throws InputError; nothing is read
// past the end.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "solvers/common/errors.h"

namespace gonogo {

class ByteWriter {
 public:
  template <typename T>
  void Put(const T& value) {
    static_assert(std::is_arithmetic_v<T>, "Put takes numbers; use the overloads for the rest");
    const char* raw = reinterpret_cast<const char*>(&value);
    bytes_.append(raw, sizeof(T));
  }
  void Put(const Eigen::Vector3d& value) {
    for (int d = 0; d < 3; ++d) Put(value[d]);
  }
  void Put(const Eigen::Matrix3d& value) {
    for (int k = 0; k < 9; ++k) Put(value.data()[k]);
  }
  void Put(const std::array<int, 3>& value) {
    for (int v : value) Put(static_cast<std::int32_t>(v));
  }
  template <typename T>
  void PutVector(const std::vector<T>& values) {
    Put(static_cast<std::uint64_t>(values.size()));
    for (const T& value : values) Put(value);
  }
  void PutTag(const char (&tag)[9]) { bytes_.append(tag, 8); }
  void PutBlob(const std::string& blob) {
    Put(static_cast<std::uint64_t>(blob.size()));
    bytes_ += blob;
  }

  std::string Take() { return std::move(bytes_); }

 private:
  std::string bytes_;
};

class ByteReader {
 public:
  explicit ByteReader(const std::string& bytes) : bytes_(bytes) {}

  template <typename T>
  void Get(T& value) {
    static_assert(std::is_arithmetic_v<T>, "Get takes numbers; use the overloads for the rest");
    Need(sizeof(T));
    std::memcpy(&value, bytes_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
  }
  void Get(Eigen::Vector3d& value) {
    for (int d = 0; d < 3; ++d) Get(value[d]);
  }
  void Get(Eigen::Matrix3d& value) {
    for (int k = 0; k < 9; ++k) Get(value.data()[k]);
  }
  void Get(std::array<int, 3>& value) {
    for (int& v : value) {
      std::int32_t stored = 0;
      Get(stored);
      v = stored;
    }
  }
  template <typename T>
  void GetVector(std::vector<T>& values, std::uint64_t expected_count) {
    std::uint64_t count = 0;
    Get(count);
    Require(count == expected_count, "state", "array length does not match the saved grain count");
    values.resize(count);
    for (T& value : values) Get(value);
  }
  // Tags are a 6-character kind and a 2-digit format version ("GNGDEM02").
  void ExpectTag(const char (&tag)[9]) {
    Need(8);
    const char* found = bytes_.data() + offset_;
    Require(std::memcmp(found, tag, 6) == 0, "state",
            std::string("not a saved ") + tag + " block (wrong or corrupt buffer)");
    Require(std::memcmp(found + 6, tag + 6, 2) == 0, "state",
            std::string("saved in format ") + std::string(found, 8) + "; this build reads " + tag +
                " only (save the state again with this build)");
    offset_ += 8;
  }
  void GetBlob(std::string& blob) {
    std::uint64_t size = 0;
    Get(size);
    Need(size);
    blob.assign(bytes_, offset_, size);
    offset_ += size;
  }
  bool AtEnd() const { return offset_ == bytes_.size(); }

 private:
  void Need(std::size_t count) const {
    Require(offset_ + count <= bytes_.size(), "state", "truncated buffer");
  }

  const std::string& bytes_;
  std::size_t offset_ = 0;
};

}  // namespace gonogo
