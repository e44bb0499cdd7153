#include "server/summary.h"

#include <google/protobuf/util/json_util.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "server/geo/products.h"

namespace gonogo::server {

using nlohmann::json;

std::string VehicleHash(const v1::Vehicle& vehicle) {
  std::string bytes;
  vehicle.SerializeToString(&bytes);
  uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

namespace {

json CriteriaJson(const mobility::Criteria& c) {
  return {{"design_slip", c.design_slip},
          {"max_slip", c.max_slip},
          {"go_margin", c.go_margin},
          {"passes", c.passes},
          {"slip_step", c.slip_step}};
}

// Rounds to `decimals` places so that the JSON prints the short decimal (27.99,
// not 27.990000000000002).
double Round(double v, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(v * scale) / scale;
}

}  // namespace

std::string BuildSummaryJson(const SummaryInputs& in) {
  const geo::Grid& grid = in.terrain.grid;
  // Cells and areas per class; cell areas vary by row in a geographic CRS.
  int64_t cells[3] = {0, 0, 0}, no_data = 0;
  double area_m2[3] = {0, 0, 0};
  double speed_sum_all = 0, speed_sum_mobile = 0;
  for (int row = 0; row < grid.height; ++row) {
    const double cell_area = grid.CellAreaM2(row);
    for (int col = 0; col < grid.width; ++col) {
      const size_t c = static_cast<size_t>(row) * grid.width + col;
      const uint8_t k = in.verdicts.go_class[c];
      if (k > 2) {
        ++no_data;
        continue;
      }
      cells[k]++;
      area_m2[k] += cell_area;
      speed_sum_all += in.verdicts.speed_kmh[c];
      if (k > 0) speed_sum_mobile += in.verdicts.speed_kmh[c];
    }
  }
  const int64_t valid = cells[0] + cells[1] + cells[2];
  const double valid_area = area_m2[0] + area_m2[1] + area_m2[2];
  const char* names[3] = {"NO-GO", "SLOW-GO", "GO"};
  json classes = json::object();
  for (int k = 2; k >= 0; --k) {
    classes[names[k]] = {{"code", k},
                         {"cells", cells[k]},
                         {"percent_of_valid", valid ? Round(100.0 * cells[k] / valid, 2) : 0.0},
                         {"area_km2", Round(area_m2[k] / 1e6, 6)}};
  }
  json by_worker = json::object();
  for (const auto& [who, n] : in.computed_by) by_worker[who] = n;

  std::string vehicle_json;
  google::protobuf::util::JsonPrintOptions opts;
  opts.preserve_proto_field_names = true;
  google::protobuf::util::MessageToJsonString(in.request.vehicle(), &vehicle_json, opts);

  json summary = {
      {"job_id", in.job_id},
      {"name", in.request.name()},
      {"grid",
       {{"width", grid.width},
        {"height", grid.height},
        {"geotransform", grid.geotransform},
        {"crs_wkt", grid.crs_wkt}}},
      {"cells",
       {{"total", static_cast<int64_t>(grid.width) * grid.height},
        {"valid", valid},
        {"no_data", no_data}}},
      {"valid_area_km2", Round(valid_area / 1e6, 6)},
      {"classes", classes},
      {"mean_speed_kmh", valid ? Round(speed_sum_all / valid, 2) : 0.0},
      {"mean_speed_kmh_where_mobile",
       cells[1] + cells[2] ? Round(speed_sum_mobile / (cells[1] + cells[2]), 2) : 0.0},
      {"no_go_cells_by_reason",
       {{"soil_cannot_carry_the_wheel", in.verdicts.no_go_cannot_carry},
        {"soft_soil_test_rci_below_vci", in.verdicts.no_go_soft_soil},
        {"drawbar_pull_below_grade_up_to_max_slip", in.verdicts.no_go_traction},
        {"soil_cannot_carry_example", in.verdicts.cannot_carry_example}}},
      {"terrain_units", in.plan.units.size()},
      {"tasks",
       {{"total", in.tasks_total},
        {"computed", in.tasks_computed},
        {"cache_hits", in.cache_hits},
        {"similarity_hits", in.similarity_hits},
        {"smallest_similarity_scale_ratio", Round(in.smallest_scale_ratio, 4)},
        {"similarity_allowed", !in.request.disable_similarity()},
        {"computed_by", by_worker}}},
      {"provenance",
       {{"tier", in.tier},
        {"tier_version", in.tier_version},
        {"gonogo_version", GONOGO_VERSION},
        {"vehicle_name", in.request.vehicle().name()},
        {"vehicle_hash", VehicleHash(in.request.vehicle())},
        {"vehicle", json::parse(vehicle_json)},
        {"criteria", CriteriaJson(in.criteria)},
        {"soft_soil_test", in.soft_soil_vci_pa > 0 ? json{{"vehicle_cone_index_kpa",
                                                           Round(in.soft_soil_vci_pa / 1000.0, 2)},
                                                          {"passes", in.criteria.passes}}
                                                   : json(nullptr)},
        {"workers", in.workers}}},
      {"elapsed_s", Round(in.elapsed_s, 3)},
  };
  return summary.dump(2);
}

std::map<std::string, std::string> ProductMetadata(const SummaryInputs& in) {
  return {{"GONOGO_JOB_ID", in.job_id},
          {"GONOGO_TIER", in.tier},
          {"GONOGO_TIER_VERSION", in.tier_version},
          {"GONOGO_VERSION", GONOGO_VERSION},
          {"GONOGO_VEHICLE", in.request.vehicle().name()},
          {"GONOGO_VEHICLE_HASH", VehicleHash(in.request.vehicle())},
          {"GONOGO_CRITERIA", CriteriaJson(in.criteria).dump()}};
}

std::string MapTitle(const SummaryInputs& in) {
  const std::string vehicle_and_tier = in.request.vehicle().name() + ", " + in.tier + " tier";
  if (in.request.name().empty()) return vehicle_and_tier;
  return in.request.name() + " - " + vehicle_and_tier;
}

std::string UtcNowRfc3339() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

std::vector<std::string> WriteJobProducts(const SummaryInputs& in, const std::string& summary_json,
                                          const std::string& datetime_utc,
                                          const std::string& out_dir) {
  namespace fs = std::filesystem;
  const std::string title = MapTitle(in);
  geo::MapProducts products =
      geo::WriteMapProducts(in.terrain.grid, in.verdicts.go_class, in.verdicts.speed_kmh,
                            {title, ProductMetadata(in)}, out_dir);
  {
    std::ofstream out(fs::path(out_dir) / "summary.json");
    out << summary_json << "\n";
    if (!out.flush()) throw std::runtime_error("cannot write summary.json in " + out_dir);
  }
  products.files.push_back(
      {"summary.json", "application/json", {"metadata"}, "Class areas, speeds, provenance"});

  // The catalogue entry carries what a search filters on: the provenance and the class areas.
  const json summary = json::parse(summary_json);
  const json properties = {
      {"description", "Off-road mobility map: go / no-go class and speed per cell"},
      {"created", datetime_utc},
      {"gonogo:job_id", in.job_id},
      {"gonogo:provenance", summary.at("provenance")},
      {"gonogo:classes", summary.at("classes")},
      {"gonogo:mean_speed_kmh", summary.at("mean_speed_kmh")},
      {"gonogo:valid_area_km2", summary.at("valid_area_km2")},
  };
  geo::WriteStacItem(in.terrain.grid, {in.job_id, datetime_utc, title, properties.dump()},
                     products.files, (fs::path(out_dir) / "item.json").string());

  std::vector<std::string> names;
  for (const geo::ProductFile& file : products.files) names.push_back(file.name);
  names.push_back("item.json");
  return names;
}

}  // namespace gonogo::server
