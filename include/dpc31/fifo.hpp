// A first-in first-out queue that keeps its storage: a vector read from `head`, emptied (not
// freed) when drained. The serial line pushes and pops thousands of items per telegram; a deque
// would allocate and free as it grows and shrinks. Storage stays bounded by what is queued: the
// consumed front is dropped once it is half of the vector (a queue that never drains, fed as
// fast as it is read, does not grow), and a vector grown beyond kKeep items is freed when the
// queue is cleared (a reset after a large queue gives the memory back).
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
    if (++head_ == v_.size()) {
      v_.clear();
      head_ = 0;
    } else if (head_ >= kKeep && head_ * 2 >= v_.size()) {
      v_.erase(v_.begin(), v_.begin() + static_cast<std::ptrdiff_t>(head_));  // amortised O(1)
      head_ = 0;
    }
  }
  void clear() {
    if (v_.capacity() > kKeep) {
      std::vector<T>().swap(v_);
    } else {
      v_.clear();
    }
    head_ = 0;
  }
  // The waiting items (snapshots read them back with clear() and resize()).
  void resize(std::size_t n) { v_.resize(head_ + n); }
  [[nodiscard]] T* begin() { return v_.data() + head_; }
  [[nodiscard]] T* end() { return v_.data() + v_.size(); }
  [[nodiscard]] const T* begin() const { return v_.data() + head_; }
  [[nodiscard]] const T* end() const { return v_.data() + v_.size(); }

 private:
  static constexpr std::size_t kKeep = 16384;  // items: more than a telegram of 255 bytes needs
  std::vector<T> v_;
  std::size_t head_ = 0;
};

}  // namespace dpc31
