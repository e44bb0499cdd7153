#include "server/task_runner.h"

#include <chrono>
#include <exception>
#include <thread>

#include "server/training_work.h"

namespace gonogo::server {

TaskResult RunTask(const TierRegistry& tiers, const TaskSpec& task,
                   const ComputeContext& context, const std::string& computed_by) {
  TaskResult result;
  result.task_id = task.task_id;
  result.computed_by = computed_by;
  const auto start = std::chrono::steady_clock::now();
  try {
    // The fault-injection delay sleeps in short steps so that cancellation still reaches it.
    for (uint32_t waited = 0; waited < task.debug_delay_ms; waited += 5) {
      if (context.Cancelled()) throw CancelledError();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (task.training) {
      result.training_output = RunTrainingWork(*task.training, context);
      result.ok = true;
      result.compute_seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      return result;
    }
    const TractionTier& tier = tiers.Get(task.tier);
    task.request.Validate();
    if (context.Cancelled()) throw CancelledError();  // cancelled while queued
    ComputeContext keeping = context;
    keeping.keep_training_histories = [&result](std::vector<std::string> histories) {
      result.training_histories = std::move(histories);
    };
    result.curve = tier.Compute(task.request, keeping);
    result.ok = true;
  } catch (...) {
    const ClassifiedError e = ClassifyCurrentException();
    result.cancelled = e.kind == ErrorKind::kCancelled;
    result.error_kind = e.kind;
    result.error_field = e.field;
    result.error = e.message;
  }
  result.compute_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace gonogo::server
