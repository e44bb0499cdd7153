// The queue of a worker pool: two lanes, cheap tasks and long ones (TaskSpec::needs: at least
// kLongTaskSeconds expected, or more than one rank). Peek/Pop alternate between the lanes while
// both hold work, so a burst of map tasks never waits behind a curve that takes an hour, and the
// hour-long curve is not starved by the burst.
#pragma once

#include <deque>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "server/worker_pool.h"

namespace gonogo::server {

inline bool IsLongTask(const TaskSpec& task) {
  return task.needs.ranks > 1 || task.needs.expected_seconds >= kLongTaskSeconds;
}

// Entry is any type with a `TaskSpec task` member. Not thread-safe: the pool's mutex guards it.
template <typename Entry>
class TwoLaneQueue {
 public:
  void Push(Entry entry) {
    (IsLongTask(entry.task) ? long_ : cheap_).push_back(std::move(entry));
  }
  bool Empty() const { return cheap_.empty() && long_.empty(); }
  size_t Size() const { return cheap_.size() + long_.size(); }

  // The entry the next Pop() returns; nullptr when empty.
  const Entry* Peek() const {
    const std::deque<Entry>* lane = NextLane();
    return lane ? &lane->front() : nullptr;
  }
  // Removes the entry Peek() shows and gives the other lane the next turn.
  Entry Pop() {
    std::deque<Entry>* lane = const_cast<std::deque<Entry>*>(NextLane());
    Entry entry = std::move(lane->front());
    lane->pop_front();
    long_turn_ = lane == &cheap_;
    return entry;
  }
  // Removes and returns the entry of `task_id`, if queued.
  std::optional<Entry> Remove(uint64_t task_id) {
    for (std::deque<Entry>* lane : {&cheap_, &long_}) {
      for (auto it = lane->begin(); it != lane->end(); ++it) {
        if (it->task.task_id != task_id) continue;
        Entry entry = std::move(*it);
        lane->erase(it);
        return entry;
      }
    }
    return std::nullopt;
  }
  // Empties both lanes, returning what they held.
  std::vector<Entry> TakeAll() {
    std::vector<Entry> all;
    for (std::deque<Entry>* lane : {&cheap_, &long_}) {
      for (Entry& e : *lane) all.push_back(std::move(e));
      lane->clear();
    }
    return all;
  }

 private:
  const std::deque<Entry>* NextLane() const {
    if (cheap_.empty() && long_.empty()) return nullptr;
    if (cheap_.empty()) return &long_;
    if (long_.empty()) return &cheap_;
    return long_turn_ ? &long_ : &cheap_;
  }

  std::deque<Entry> cheap_, long_;
  bool long_turn_ = false;
};

}  // namespace gonogo::server
