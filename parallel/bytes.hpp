#pragma once
// Packing typed arrays into the byte messages of parallel::Communicator's
// exchanges and reading them back, with memcpy: a message's arrays follow one
// another, so an element need not be aligned for its type.
#include <cstddef>
#include <cstring>
#include <span>
#include <vector>

namespace floesim::parallel {

// Copies count T's to `out` and returns the end of what it wrote.
template <class T>
std::byte* put(std::byte* out, const T* data, std::size_t count) {
  if (count > 0) std::memcpy(out, data, count * sizeof(T));
  return out + count * sizeof(T);
}

// Element j of an array of T that starts at `in` (any alignment).
template <class T>
T at(const std::byte* in, std::size_t j) {
  T value;
  std::memcpy(&value, in + j * sizeof(T), sizeof(T));
  return value;
}

// Appends the bytes of `values` to a message being built.
template <class T>
void append(std::vector<std::byte>& out, std::span<const T> values) {
  // resize + memcpy rather than insert of a byte range: GCC 12 reports a
  // false -Wstringop-overflow on the inlined range insert.
  const std::size_t bytes = values.size() * sizeof(T);
  if (bytes == 0) return;
  const std::size_t end = out.size();
  out.resize(end + bytes);
  std::memcpy(out.data() + end, values.data(), bytes);
}

// Reads `count` T's from `in` into a vector and moves `in` past them.
template <class T>
std::vector<T> take(const std::byte*& in, std::size_t count) {
  std::vector<T> values(count);
  if (count > 0) std::memcpy(static_cast<void*>(values.data()), in, count * sizeof(T));
  in += count * sizeof(T);
  return values;
}

}  // namespace floesim::parallel
