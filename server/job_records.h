// The API form of stored jobs, shared by the job manager's map and curve halves.
#pragma once

#include <cstdint>

#include "cache/job_store.h"
#include "gonogo/v1/mobility.pb.h"

namespace gonogo::server {

int64_t NowMs();  // Unix time, ms
v1::JobStatus StatusOf(const cache::JobRecord& record);
v1::Job JobOf(const cache::JobRecord& record);

}  // namespace gonogo::server
