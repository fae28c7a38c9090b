#pragma once
/// @file
/// A first-in first-out work list of ids (candidates, tets) that holds each id at most once at a
/// time: the fixpoint loops push whatever a change may affect and pop until nothing is left.

#include <deque>
#include <vector>

#include "hexmerge/core/index.h"

namespace hexmerge {

/// Ids in [0, nb_ids) in the order first pushed; pushing an id already waiting does nothing,
/// an id popped may be pushed again.
class WorkQueue {
 public:
  explicit WorkQueue(std::size_t nb_ids) : queued_(nb_ids, 0) {}
  void push(index_t i) {
    if (queued_[i]) return;
    queued_[i] = 1;
    items_.push_back(i);
  }
  bool empty() const { return items_.empty(); }
  index_t pop() {
    const index_t i = items_.front();
    items_.pop_front();
    queued_[i] = 0;
    return i;
  }

 private:
  std::deque<index_t> items_;
  std::vector<char> queued_;
};

}  // namespace hexmerge
