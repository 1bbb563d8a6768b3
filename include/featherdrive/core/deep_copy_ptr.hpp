// A pointer that owns its object and copies it with itself, so that a class may hold a member
// whose type its header only declares (Simulation's workspace). The class's copy, move and
// destructor must then be defined where T is complete.
#pragma once

#include <memory>
#include <utility>

namespace featherdrive {

template <class T>
class DeepCopyPtr {
 public:
  DeepCopyPtr() = default;
  explicit DeepCopyPtr(std::unique_ptr<T> p) noexcept : p_(std::move(p)) {}
  DeepCopyPtr(const DeepCopyPtr& other) : p_(other.p_ ? std::make_unique<T>(*other.p_) : nullptr) {}
  DeepCopyPtr(DeepCopyPtr&&) noexcept = default;
  /// Assigns into the object there is (as a member of the class would be assigned).
  DeepCopyPtr& operator=(const DeepCopyPtr& other) {
    if (this == &other) return *this;
    if (p_ && other.p_)
      *p_ = *other.p_;
    else
      p_ = other.p_ ? std::make_unique<T>(*other.p_) : nullptr;
    return *this;
  }
  DeepCopyPtr& operator=(DeepCopyPtr&&) noexcept = default;

  T& operator*() { return *p_; }
  const T& operator*() const { return *p_; }
  T* operator->() { return p_.get(); }
  const T* operator->() const { return p_.get(); }

 private:
  std::unique_ptr<T> p_;
};

}  // namespace featherdrive
