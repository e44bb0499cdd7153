// summary.json of a map job and the metadata stamped into its rasters.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "gonogo/v1/mobility.pb.h"
#include "server/map_plan.h"

namespace gonogo::server {

struct SummaryInputs {
  std::string job_id;
  const v1::MapRequest& request;
  std::string tier;
  std::string tier_version;
  std::string workers;  // the pool, in words
  const MapPlan& plan;
  const geo::TerrainLayers& terrain;
  const MapVerdicts& verdicts;
  size_t tasks_total;
  size_t tasks_computed;
  size_t cache_hits;
  size_t similarity_hits;
  double smallest_scale_ratio;                 // of the similarity hits (1 when none)
  std::map<std::string, int64_t> computed_by;  // "rank 1" -> tasks
  double soft_soil_vci_pa;                     // 0: no soft-soil test
  mobility::Criteria criteria;
  double elapsed_s;
};

// FNV-1a 64 of the vehicle message's serialised form, as 16 hex digits.
std::string VehicleHash(const v1::Vehicle& vehicle);
std::string BuildSummaryJson(const SummaryInputs& in);
std::map<std::string, std::string> ProductMetadata(const SummaryInputs& in);

// "<name> - <vehicle>, <tier> tier" (without the name when the request has none): the title of the
// quicklook, the KMZ legend and the STAC item.
std::string MapTitle(const SummaryInputs& in);

// Writes every product of a finished map job into out_dir: the map products (geo/products.h),
// `summary_json` as summary.json, and item.json, the STAC item describing them all with the
// summary's provenance and class areas as properties ("gonogo:" prefix) and `datetime_utc` (RFC
// 3339) as its time. Returns the product file names in download order.
std::vector<std::string> WriteJobProducts(const SummaryInputs& in, const std::string& summary_json,
                                          const std::string& datetime_utc,
                                          const std::string& out_dir);

// Now, in UTC, as RFC 3339 to the second ("2024-05-01T12:00:00Z").
std::string UtcNowRfc3339();

}  // namespace gonogo::server
