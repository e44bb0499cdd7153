#include "server/stall_watch.h"

#include <algorithm>

#include <spdlog/spdlog.h>

namespace gonogo::server {

StallWatch::Guard::Guard(StallWatch& watch, grpc::ServerContext* context) : watch_(watch) {
  std::lock_guard<std::mutex> lock(watch_.mutex_);
  id_ = watch_.next_id_++;
  watch_.entries_[id_] = Entry{context, context->peer(), Clock::now()};
}

StallWatch::Guard::~Guard() {
  std::lock_guard<std::mutex> lock(watch_.mutex_);
  watch_.entries_.erase(id_);
}

void StallWatch::Guard::Touch() {
  std::lock_guard<std::mutex> lock(watch_.mutex_);
  watch_.entries_.at(id_).last = Clock::now();
}

bool StallWatch::Guard::stalled() const {
  std::lock_guard<std::mutex> lock(watch_.mutex_);
  return watch_.entries_.at(id_).stalled;
}

StallWatch::StallWatch(std::chrono::milliseconds limit) : limit_(limit), thread_([this] { Loop(); }) {}

StallWatch::~StallWatch() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void StallWatch::Loop() {
  // Checked a few times per limit, so that a stalled stream ends within 1.25 limits.
  const auto period = std::clamp(limit_ / 4, std::chrono::milliseconds(10), std::chrono::milliseconds(1000));
  std::unique_lock<std::mutex> lock(mutex_);
  while (!changed_.wait_for(lock, period, [this] { return stopping_; })) {
    const Clock::time_point now = Clock::now();
    for (auto& [id, entry] : entries_) {
      if (!entry.stalled && now - entry.last > limit_) {
        entry.stalled = true;
        spdlog::warn("a stream from {} sent or read nothing for {} s: cancelled (gonogo-server --stream-stall-s)",
                     entry.peer, limit_.count() / 1000.0);
        entry.context->TryCancel();
      }
    }
  }
}

}  // namespace gonogo::server
