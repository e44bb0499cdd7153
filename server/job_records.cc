#include "server/job_records.h"

#include <chrono>

namespace gonogo::server {

int64_t NowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

v1::JobStatus StatusOf(const cache::JobRecord& j) {
  v1::JobStatus s;
  s.set_job_id(j.id);
  s.set_state(static_cast<v1::JobState>(j.state));
  s.set_fraction_done(j.fraction_done);
  s.set_tasks_done(static_cast<uint32_t>(j.tasks_done));
  s.set_tasks_total(static_cast<uint32_t>(j.tasks_total));
  s.set_cache_hits(static_cast<uint32_t>(j.cache_hits));
  s.set_similarity_hits(static_cast<uint32_t>(j.similarity_hits));
  s.set_message(j.message);
  return s;
}

v1::Job JobOf(const cache::JobRecord& j) {
  v1::Job out;
  out.set_job_id(j.id);
  out.set_name(j.name);
  out.set_tier(j.tier);
  *out.mutable_status() = StatusOf(j);
  out.set_created_unix_ms(j.created_unix_ms);
  out.set_finished_unix_ms(j.finished_unix_ms);
  for (const auto& p : j.products) out.add_products(p);
  out.set_summary_json(j.summary_json);
  out.set_kind(j.kind);
  out.set_owner(j.owner);
  return out;
}

}  // namespace gonogo::server
