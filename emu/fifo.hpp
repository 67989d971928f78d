// A first-in first-out queue that keeps its storage: a vector read from `head`, emptied (not
// freed) when drained. The serial line pushes and pops thousands of items per telegram; a deque
// would allocate and free as it grows and shrinks.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace dpc31 {

template <typename T>
class Fifo {
 public:
  [[nodiscard]] bool empty() const { return head_ == v_.size(); }
  [[nodiscard]] std::size_t size() const { return v_.size() - head_; }
  [[nodiscard]] const T& front() const { return v_[head_]; }
  template <typename... A>
  T& emplace_back(A&&... a) {
    return v_.emplace_back(std::forward<A>(a)...);
  }
  void pop_front() {
    if (++head_ == v_.size()) clear();
  }
  void clear() {
    v_.clear();
    head_ = 0;
  }
  // The waiting items (snapshots read them back with clear() and resize()).
  void resize(std::size_t n) { v_.resize(head_ + n); }
  [[nodiscard]] T* begin() { return v_.data() + head_; }
  [[nodiscard]] T* end() { return v_.data() + v_.size(); }
  [[nodiscard]] const T* begin() const { return v_.data() + head_; }
  [[nodiscard]] const T* end() const { return v_.data() + v_.size(); }

 private:
  std::vector<T> v_;
  std::size_t head_ = 0;
};

}  // namespace dpc31
