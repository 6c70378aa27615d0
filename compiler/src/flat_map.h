// SPDX-License-Identifier: MIT
// flat_map.h (private to the compiler's stages): a hash map in one array
// (open addressing, linear probing) for the stages that look keys up
// millions of times, where std::unordered_map's node per key and division
// per lookup cost more than the work around them. No erase; no iteration,
// so nothing a stage computes can depend on the table's order.
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace bspc {

// `Hash` gives a 64-bit hash of a key; its high bits pick the slot
// (Fibonacci hashing), so a hash whose low bits are poor still spreads.
template <typename Key, typename Value, typename Hash>
class FlatMap {
 public:
  // Room for `expected` keys without growing.
  explicit FlatMap(std::size_t expected = 0) { allocate(expected); }

  // The value of `key`, or nullptr.
  const Value* find(const Key& key) const {
    for (std::size_t i = slotOf(key);; i = (i + 1) & mask_) {
      const Slot& slot = slots_[i];
      if (!slot.used) return nullptr;
      if (slot.key == key) return &slot.value;
    }
  }

  // The value of `key`, inserted as `value` when absent, and whether it was
  // inserted. The pointer holds until the next insertion.
  std::pair<Value*, bool> tryEmplace(const Key& key, const Value& value) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    for (std::size_t i = slotOf(key);; i = (i + 1) & mask_) {
      Slot& slot = slots_[i];
      if (!slot.used) {
        slot = {key, value, true};
        ++size_;
        return {&slot.value, true};
      }
      if (slot.key == key) return {&slot.value, false};
    }
  }

  std::size_t size() const { return size_; }

 private:
  struct Slot {
    Key key{};
    Value value{};
    bool used = false;
  };

  std::size_t slotOf(const Key& key) const {
    return std::size_t((std::uint64_t(Hash{}(key)) * 0x9E3779B97F4A7C15ull) >> shift_);
  }

  // At most half full: a miss ends after a short run of slots.
  void allocate(std::size_t expected) {
    const std::size_t slots = std::bit_ceil(std::max<std::size_t>(16, 2 * expected));
    slots_.assign(slots, Slot{});
    mask_ = slots - 1;
    shift_ = 64 - std::countr_zero(slots);
    size_ = 0;
  }

  void grow() {
    std::vector<Slot> old = std::move(slots_);
    allocate(old.size());
    for (const Slot& slot : old)
      if (slot.used) tryEmplace(slot.key, slot.value);
  }

  std::vector<Slot> slots_;
  std::size_t mask_ = 0;
  int shift_ = 64;
  std::size_t size_ = 0;
};

}  // namespace bspc
