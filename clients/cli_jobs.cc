// gonogo map | jobs | watch ID | cancel ID | download ID --out DIR
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <utility>
#include <vector>

#include "clients/cli_commands.h"

namespace gonogo::cli {
namespace {

namespace fs = std::filesystem;

constexpr size_t kChunkBytes = 1 << 20;

struct MapOptions {
  SurrogateOptions surrogate;   // fe-ann
  std::string cone_index_file;  // GeoTIFF, kPa
  std::string slope_file;       // GeoTIFF, percent
  std::string elevation_file;   // GeoTIFF, m
  std::string soil_class_file;  // GeoTIFF of soil class codes
  std::string soil_table_file;  // JSON SoilTable
  std::string vehicle_file;
  std::string tier;
  std::string out_dir;
  std::string name;
  unsigned passes = 0;  // 0: the server's default, 1
  double design_slip = 0;
  double max_slip = 0;
  double go_margin = 0;
  double slip_step = 0;
  bool no_wait = false;
  bool no_similarity = false;
};

using Rasters = std::vector<std::pair<v1::RasterRole, std::string>>;  // role, bytes

void AddMapInputs(CLI::App& map, MapOptions* o) {
  const std::string group = "Inputs (GeoTIFFs on one grid)";
  map.add_option("--cone-index", o->cone_index_file, "raster of cone index, kPa")
      ->required()
      ->type_name("FILE")
      ->check(InputFile())
      ->group(group);
  auto* slope = map.add_option("--slope", o->slope_file, "raster of slope, percent")
                    ->type_name("FILE")
                    ->check(InputFile())
                    ->group(group);
  map.add_option("--elevation", o->elevation_file, "raster of elevation, m (slope is derived)")
      ->type_name("FILE")
      ->check(InputFile())
      ->group(group)
      ->excludes(slope);
  auto* soil_class =
      map.add_option("--soil-class", o->soil_class_file, "raster of integer soil class codes")
          ->type_name("FILE")
          ->check(InputFile())
          ->group(group);
  auto* soil_table = map.add_option("--soil-table", o->soil_table_file,
                                    "JSON soil table naming the classes' soils")
                         ->type_name("FILE")
                         ->check(InputFile())
                         ->group(group)
                         ->needs(soil_class);
  soil_class->needs(soil_table);
  map.add_option("--vehicle", o->vehicle_file, "vehicle JSON (clients/vehicles/*.json)")
      ->required()
      ->type_name("FILE")
      ->check(InputFile())
      ->group(group);
}

void AddMapCriteria(CLI::App& map, MapOptions* o) {
  const std::string group = "Criteria";
  map.add_option("--passes", o->passes, "NRMM soft-soil test passes (default 1)")
      ->type_name("1|50")
      ->check(CLI::Validator(CLI::IsMember({1u, 50u})).description(""))
      ->group(group);
  map.add_option("--design-slip", o->design_slip,
                 "slip at which GO needs the margin, 0..1 (default 0.20)")
      ->type_name("S")
      ->check(Fraction())
      ->group(group);
  map.add_option("--max-slip", o->max_slip,
                 "highest slip the vehicle may run at, 0..1 (default 0.50)")
      ->type_name("S")
      ->check(Fraction())
      ->group(group);
  map.add_option("--go-margin", o->go_margin,
                 "drawbar-pull coefficient D/W needed above the grade at the design "
                 "slip for GO, - (default 0.05)")
      ->type_name("D/W")
      ->group(group);
  map.add_option("--slip-step", o->slip_step, "spacing of the slip sweep, 0..1 (default 0.05)")
      ->type_name("S")
      ->check(Fraction())
      ->group(group);
}

v1::MapRequest MapRequestFromOptions(const MapOptions& o) {
  v1::MapRequest request;
  request.set_name(o.name.empty() ? "map " + fs::path(o.cone_index_file).stem().string() : o.name);
  request.set_tier(o.tier);
  request.set_disable_similarity(o.no_similarity);
  request.set_surrogate_model(o.surrogate.model);
  *request.mutable_surrogate_guard() = GuardFromOptions(o.surrogate);
  *request.mutable_vehicle() = ReadJson<v1::Vehicle>(o.vehicle_file, "vehicle file");
  if (!o.soil_table_file.empty()) {
    *request.mutable_soil_table() = ReadJson<v1::SoilTable>(o.soil_table_file, "soil table");
  }
  v1::Criteria* c = request.mutable_criteria();
  c->set_passes(o.passes);
  c->set_design_slip(o.design_slip);
  c->set_max_slip(o.max_slip);
  c->set_go_margin(o.go_margin);
  c->set_slip_step(o.slip_step);
  return request;
}

Rasters ReadRasters(const MapOptions& o) {
  if (o.slope_file.empty() && o.elevation_file.empty()) {
    throw UsageError("give exactly one of --slope FILE or --elevation FILE");
  }
  const std::vector<std::pair<v1::RasterRole, std::string>> files = {
      {v1::RASTER_ROLE_CONE_INDEX, o.cone_index_file},
      {v1::RASTER_ROLE_SLOPE, o.slope_file},
      {v1::RASTER_ROLE_ELEVATION, o.elevation_file},
      {v1::RASTER_ROLE_SOIL_CLASS, o.soil_class_file}};
  Rasters rasters;
  for (const auto& [role, path] : files) {
    if (!path.empty()) rasters.emplace_back(role, ReadFile(path, "raster"));
  }
  return rasters;
}

// Streams the request, then each raster in chunks.
grpc::Status SubmitMap(Client& client, const v1::MapRequest& request, const Rasters& rasters,
                       v1::Job* job) {
  grpc::ClientContext ctx;
  auto writer = client.stub().SubmitMap(&ctx, job);
  v1::SubmitMapRequest first;
  *first.mutable_request() = request;
  bool ok = writer->Write(first);
  for (const auto& [role, bytes] : rasters) {
    for (size_t off = 0; ok && off < bytes.size(); off += kChunkBytes) {
      v1::SubmitMapRequest m;
      m.mutable_chunk()->set_role(role);
      m.mutable_chunk()->set_data(bytes.substr(off, kChunkBytes));
      ok = writer->Write(m);
    }
  }
  writer->WritesDone();
  return writer->Finish();
}

int RunMap(Client& client, const MapOptions& o) {
  const v1::MapRequest request = MapRequestFromOptions(o);
  const Rasters rasters = ReadRasters(o);
  v1::Job job;
  const grpc::Status submitted = SubmitMap(client, request, rasters, &job);
  if (!submitted.ok()) return Fail(submitted);
  std::cerr << "submitted " << job.job_id() << " (" << request.tier() << ", "
            << request.vehicle().name() << ")\n";
  std::cout << job.job_id() << std::endl;
  if (o.no_wait) return kExitOk;
  if (const int rc = client.WaitUntilDone(job.job_id(), "job"); rc != kExitOk) return rc;
  std::vector<std::string> written;
  const grpc::Status fetched = client.Download(job.job_id(), o.out_dir, &written);
  if (!fetched.ok()) return Fail(fetched);
  for (const auto& f : written) std::cerr << "wrote " << f << "\n";
  return kExitOk;
}

int RunJobs(Client& client, unsigned limit) {
  grpc::ClientContext ctx;
  v1::ListJobsRequest req;
  req.set_limit(limit);
  v1::ListJobsResponse resp;
  const grpc::Status s = client.stub().ListJobs(&ctx, req, &resp);
  if (!s.ok()) return Fail(s);
  // An admin sees every identity's jobs: then each line says whose it is.
  bool several_owners = false;
  for (const auto& j : resp.jobs()) several_owners |= j.owner() != resp.jobs(0).owner();
  std::cout << std::left << std::setw(18) << "JOB" << std::setw(11) << "STATE" << std::setw(11)
            << "TIER" << std::setw(7) << "DONE" << std::setw(13) << "TASKS"
            << (several_owners ? "OWNER: " : "") << "NAME / MESSAGE\n";
  for (const auto& j : resp.jobs()) {
    std::ostringstream tasks;
    tasks << j.status().tasks_done() << "/" << j.status().tasks_total();
    std::cout << std::left << std::setw(18) << j.job_id() << std::setw(11)
              << StateName(j.status().state()) << std::setw(11) << j.tier() << std::setw(7)
              << (std::to_string(static_cast<int>(100 * j.status().fraction_done())) + "%")
              << std::setw(13) << tasks.str() << (several_owners ? j.owner() + ": " : "") << j.name()
              << " / " << j.status().message() << "\n";
  }
  return kExitOk;
}

int RunWatch(Client& client, const std::string& id) {
  v1::JobStatus last;
  const grpc::Status s = client.Watch(id, &last);
  if (!s.ok()) return Fail(s);
  std::cout << id << " " << StateName(last.state()) << ": " << last.message() << "\n";
  return last.state() == v1::JOB_STATE_DONE ? kExitOk : kExitJobFailed;
}

int RunCancel(Client& client, const std::string& id) {
  grpc::ClientContext ctx;
  v1::CancelJobRequest req;
  req.set_job_id(id);
  v1::Job job;
  const grpc::Status s = client.stub().CancelJob(&ctx, req, &job);
  if (!s.ok()) return Fail(s);
  std::cout << job.job_id() << " " << StateName(job.status().state()) << ": "
            << job.status().message() << "\n";
  return kExitOk;
}

int RunDelete(Client& client, const std::string& id) {
  grpc::ClientContext ctx;
  v1::DeleteJobRequest req;
  req.set_job_id(id);
  v1::DeleteJobResponse response;
  const grpc::Status s = client.stub().DeleteJob(&ctx, req, &response);
  if (!s.ok()) return Fail(s);
  std::cout << id << " deleted, " << std::fixed << std::setprecision(1)
            << response.bytes_freed() / 1048576.0 << " MiB freed\n";
  return kExitOk;
}

int RunDownload(Client& client, const std::string& id, const std::string& out_dir) {
  std::vector<std::string> written;
  const grpc::Status s = client.Download(id, out_dir, &written);
  if (!s.ok()) return Fail(s);
  for (const auto& f : written) std::cout << f << "\n";
  return kExitOk;
}

// The job id every job command but `jobs` takes.
void AddJobId(CLI::App& app, std::string* id) {
  app.add_option("ID", *id, "job id (gonogo jobs lists them)")->required();
}

}  // namespace

Command AddMapCommand(CLI::App& parent) {
  auto o = std::make_shared<MapOptions>();
  CLI::App* map =
      parent.add_subcommand("map", "GO/NO-GO and speed maps of a terrain for a vehicle (a job)");
  map->footer(
      "Submits the job, shows its progress, then downloads its products into --out.\n"
      "Give exactly one of --slope and --elevation; --soil-class and --soil-table go "
      "together.\nWith --no-wait the job id is printed and the command returns "
      "(gonogo watch / download ID).");
  AddMapInputs(*map, o.get());
  map->add_option("--tier", o->tier, "traction tier (gonogo tiers lists them)")
      ->required()
      ->type_name("T");
  AddSurrogateOptions(*map, &o->surrogate,
                      "the surrogate model for every soil (gonogo models lists them); default: "
                      "each soil's best");
  map->add_option("--out", o->out_dir, "directory for the products")->required()->type_name("DIR");
  map->add_option("--name", o->name, "free text shown in job lists; default: map CONE_INDEX_STEM")
      ->type_name("TEXT");
  AddMapCriteria(*map, o.get());
  map->add_flag("--no-wait", o->no_wait, "print the job id and return");
  map->add_flag("--no-similarity", o->no_similarity,
                "answer only from exact cache keys or fresh computation");
  return {map, [o](Client& client) { return RunMap(client, *o); }};
}

Command AddJobsCommand(CLI::App& parent) {
  auto limit = std::make_shared<unsigned>(50);
  CLI::App* jobs = parent.add_subcommand("jobs", "list jobs, newest first");
  jobs->add_option("--limit", *limit, "at most this many jobs")
      ->type_name("N")
      ->capture_default_str();
  return {jobs, [limit](Client& client) { return RunJobs(client, *limit); }};
}

Command AddWatchCommand(CLI::App& parent) {
  auto id = std::make_shared<std::string>();
  CLI::App* watch = parent.add_subcommand("watch", "follow a job's progress until it ends");
  watch->footer("Exits 1 when the job failed or was cancelled.");
  AddJobId(*watch, id.get());
  return {watch, [id](Client& client) { return RunWatch(client, *id); }};
}

Command AddCancelCommand(CLI::App& parent) {
  auto id = std::make_shared<std::string>();
  CLI::App* cancel = parent.add_subcommand("cancel", "cancel a queued or running job");
  AddJobId(*cancel, id.get());
  return {cancel, [id](Client& client) { return RunCancel(client, *id); }};
}

Command AddDeleteCommand(CLI::App& parent) {
  auto id = std::make_shared<std::string>();
  CLI::App* del = parent.add_subcommand(
      "delete", "delete an ended job: its record, inputs and products (its curves stay cached)");
  AddJobId(*del, id.get());
  return {del, [id](Client& client) { return RunDelete(client, *id); }};
}

Command AddDownloadCommand(CLI::App& parent) {
  struct Options {
    std::string id, out_dir;
  };
  auto o = std::make_shared<Options>();
  CLI::App* download = parent.add_subcommand("download", "fetch a finished job's products");
  AddJobId(*download, &o->id);
  download->add_option("--out", o->out_dir, "directory for the products (created when missing)")
      ->required()
      ->type_name("DIR");
  return {download, [o](Client& client) { return RunDownload(client, o->id, o->out_dir); }};
}

}  // namespace gonogo::cli
