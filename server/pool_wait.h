// Runs tasks on the worker pool and waits for all of them: for RPCs that answer with curves
// (GetTractionCurve, RunScalability). The handler thread waits on results, never runs a solver.
#pragma once

#include <chrono>
#include <functional>
#include <vector>

#include "server/worker_pool.h"

namespace gonogo::server {

// Submits every task and returns their results in the same order. When `abandon` turns true or the
// deadline passes, the outstanding tasks are cancelled and their results come back cancelled.
std::vector<TaskResult> RunAndWait(WorkerPool& pool, std::vector<TaskSpec> tasks,
                                   std::chrono::steady_clock::time_point deadline,
                                   const std::function<bool()>& abandon);

}  // namespace gonogo::server
