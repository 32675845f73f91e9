// Handle bookkeeping for dense SoA storage with swap-remove: a handle's index
// maps to a slot; a generation (never 0) detects stale handles. Freed indices are
// reused last-in first-out, so handle values are deterministic.
#pragma once

#include <cstdint>
#include <vector>

namespace impact::host {

class HandleTable {
 public:
  static constexpr uint32_t kNoSlot = 0xffffffffu;

  /// A fresh (index, generation) bound to slot.
  void acquire(uint32_t slot, uint32_t* index, uint32_t* generation) {
    uint32_t i;
    if (!free_.empty()) {
      i = free_.back();
      free_.pop_back();
    } else {
      i = static_cast<uint32_t>(slot_.size());
      slot_.push_back(kNoSlot);
      gen_.push_back(1);
    }
    slot_[i] = slot;
    *index = i;
    *generation = gen_[i];
  }

  /// Slot of a live handle, or kNoSlot.
  uint32_t lookup(uint32_t index, uint32_t generation) const {
    if (generation == 0 || index >= slot_.size() || gen_[index] != generation) return kNoSlot;
    return slot_[index];
  }

  void rebind(uint32_t index, uint32_t slot) { slot_[index] = slot; }

  /// Kills the handle: its generation moves on (skipping 0) and the index is reused later.
  void release(uint32_t index) {
    slot_[index] = kNoSlot;
    gen_[index] = gen_[index] + 1 == 0 ? 1 : gen_[index] + 1;
    free_.push_back(index);
  }

 private:
  std::vector<uint32_t> slot_;
  std::vector<uint32_t> gen_;
  std::vector<uint32_t> free_;
};

}  // namespace impact::host
