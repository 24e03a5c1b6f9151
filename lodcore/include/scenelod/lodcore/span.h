#pragma once
// Non-owning views over caller memory: Span (pointer + count) and StridedSpan (pointer + count +
// byte stride, so interleaved vertex buffers pass without a copy).
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

namespace scenelod {

template <class T>
struct Span {
  T* data = nullptr;
  size_t count = 0;

  constexpr Span() = default;
  constexpr Span(T* d, size_t n) : data(d), count(n) {}
  // any contiguous container with data() and size() (std::vector, std::array)
  template <class C, class = decltype(static_cast<T*>(std::declval<C&>().data()))>
  constexpr Span(C& c) : data(c.data()), count(c.size()) {}

  constexpr T& operator[](size_t i) const { return data[i]; }
  constexpr T* begin() const { return data; }
  constexpr T* end() const { return data + count; }
  constexpr size_t size() const { return count; }
  constexpr bool empty() const { return count == 0; }
  constexpr Span subspan(size_t first, size_t n) const { return Span(data + first, n); }
};

template <class T>
struct StridedSpan {
  T* data = nullptr;
  size_t count = 0;
  size_t stride = sizeof(T);  // bytes between consecutive elements

  constexpr StridedSpan() = default;
  constexpr StridedSpan(T* d, size_t n, size_t byte_stride = sizeof(T)) : data(d), count(n), stride(byte_stride) {}
  constexpr StridedSpan(Span<T> s) : data(s.data), count(s.count), stride(sizeof(T)) {}

  T& operator[](size_t i) const {
    using Byte = typename std::conditional<std::is_const<T>::value, const unsigned char, unsigned char>::type;
    return *reinterpret_cast<T*>(reinterpret_cast<Byte*>(data) + i * stride);
  }
  constexpr size_t size() const { return count; }
  constexpr bool empty() const { return count == 0; }
};

}  // namespace scenelod
