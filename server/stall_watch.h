// Streams that stop moving: an upload whose client sends nothing more, a download whose client reads
// nothing more. Each holds a server thread (the synchronous server's model), so a stream without a
// message for longer than the limit is cancelled (grpc::ServerContext::TryCancel, which unblocks the
// handler's Read or Write) and its handler cleans up as for any cancelled call.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include <grpcpp/server_context.h>

namespace gonogo::server {

class StallWatch {
 public:
  using Clock = std::chrono::steady_clock;

  // One watched stream: registered on construction, released on destruction.
  class Guard {
   public:
    Guard(StallWatch& watch, grpc::ServerContext* context);
    ~Guard();
    Guard(const Guard&) = delete;
    Guard& operator=(const Guard&) = delete;
    // A message went through: the stall clock starts again.
    void Touch();
    // True when the watch cancelled the stream for stalling.
    bool stalled() const;

   private:
    StallWatch& watch_;
    uint64_t id_;
  };

  explicit StallWatch(std::chrono::milliseconds limit);
  ~StallWatch();
  std::chrono::milliseconds limit() const { return limit_; }

 private:
  struct Entry {
    grpc::ServerContext* context;
    std::string peer;
    Clock::time_point last;
    bool stalled = false;
  };
  void Loop();

  const std::chrono::milliseconds limit_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::map<uint64_t, Entry> entries_;
  uint64_t next_id_ = 1;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace gonogo::server
