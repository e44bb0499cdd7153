// gonogo: command-line client of gonogo-server.
//
//   gonogo [--server HOST:PORT|@ENDPOINT_FILE] map --cone-index FILE (--slope FILE | --elevation FILE)
//          [--soil-class FILE --soil-table FILE] --vehicle FILE --tier empirical --out DIR
//   gonogo jobs | watch ID | cancel ID | download ID --out DIR
//   gonogo curve --tier T (--vehicle FILE [--axle N] | --wheel-diameter M --wheel-width M
//          --section-height M --deflection M --wheel-load N) --cone-index KPA [--slip-step S] [--csv]
#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "gonogo/v1/mobility.grpc.pb.h"

namespace {

namespace fs = std::filesystem;
namespace v1 = gonogo::v1;

constexpr size_t kChunkBytes = 1 << 20;

const char* kUsage =
    "usage: gonogo [--server HOST:PORT | --server @ENDPOINT_FILE] COMMAND [options]\n"
    "commands:\n"
    "  map       --cone-index FILE (--slope FILE | --elevation FILE) [--soil-class FILE\n"
    "            --soil-table FILE] --vehicle FILE --tier T --out DIR [--name TEXT] [--passes 1|50]\n"
    "            [--design-slip S] [--max-slip S] [--go-margin M] [--slip-step S] [--no-wait]\n"
    "            rasters are GeoTIFFs: cone index in kPa, slope in percent, elevation in m\n"
    "  jobs      [--limit N]                 list jobs, newest first\n"
    "  tiers                                 the server's traction tiers: model, inputs, cost\n"
    "  watch     ID                          follow a job's progress until it ends\n"
    "  cancel    ID                          cancel a queued or running job\n"
    "  download  ID --out DIR                fetch a finished job's products\n"
    "  curve     --tier T (--vehicle FILE [--axle N] | --wheel-diameter M --wheel-width M\n"
    "            [--section-height M --deflection M] --wheel-load N [--rolling-radius M]\n"
    "            [--inflation-pressure-kpa P]) (--cone-index KPA | --soil NAME |\n"
    "            --bekker n=N,kc=KC,kphi=KPHI,c=C,phi_deg=PHI,K=K) [--slip-step S] [--csv]\n"
    "            [--no-similarity]\n"
    "            Bekker parameters in SI: kc N/m^(n+1), kphi N/m^(n+2), c Pa, phi degrees, K m;\n"
    "            without --section-height the wheel is rigid (h = d/4 is sent, deflection 0)\n"
    "  scalability --tier T (wheel and soil options as for curve) [--scales 1,0.7,0.5,0.25]\n"
    "            [--slip-step S] --out DIR   seed 001's scaled-tyre study: loads by equal W/(b d)\n"
    "The server defaults to $GONOGO_SERVER, else 127.0.0.1:50051.\n";

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Options after the command: --name value pairs and bare flags.
struct Args {
  std::map<std::string, std::string> values;
  std::vector<std::string> positional;

  bool Has(const std::string& k) const { return values.count(k) > 0; }
  std::string Get(const std::string& k, const std::string& fallback = "") const {
    auto it = values.find(k);
    return it == values.end() ? fallback : it->second;
  }
  std::string Need(const std::string& k) const {
    if (!Has(k)) throw UsageError("--" + k + " is required");
    return Get(k);
  }
  double Number(const std::string& k, double fallback) const {
    if (!Has(k)) return fallback;
    try {
      size_t used = 0;
      const double v = std::stod(Get(k), &used);
      if (used != Get(k).size()) throw std::invalid_argument("");
      return v;
    } catch (const std::logic_error&) {
      throw UsageError("--" + k + " needs a number, got '" + Get(k) + "'");
    }
  }
};

Args ParseArgs(const std::vector<std::string>& argv, const std::vector<std::string>& flags) {
  Args a;
  for (size_t i = 0; i < argv.size(); ++i) {
    const std::string& s = argv[i];
    if (s.rfind("--", 0) == 0) {
      const std::string key = s.substr(2);
      if (std::find(flags.begin(), flags.end(), key) != flags.end()) {
        a.values[key] = "1";
      } else if (i + 1 < argv.size()) {
        a.values[key] = argv[++i];
      } else {
        throw UsageError(s + " needs a value");
      }
    } else {
      a.positional.push_back(s);
    }
  }
  return a;
}

std::string ReadFile(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError(what + ": cannot read " + path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

template <typename Message>
Message ReadJson(const std::string& path, const std::string& what) {
  Message m;
  google::protobuf::util::JsonParseOptions opts;
  opts.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(ReadFile(path, what), &m, opts);
  if (!status.ok()) throw UsageError(what + " " + path + ": " + std::string(status.message()));
  return m;
}

int Fail(const grpc::Status& s) {
  static const char* kNames[] = {"OK", "CANCELLED", "UNKNOWN", "INVALID_ARGUMENT",
                                 "DEADLINE_EXCEEDED", "NOT_FOUND", "ALREADY_EXISTS",
                                 "PERMISSION_DENIED", "RESOURCE_EXHAUSTED", "FAILED_PRECONDITION",
                                 "ABORTED", "OUT_OF_RANGE", "UNIMPLEMENTED", "INTERNAL",
                                 "UNAVAILABLE", "DATA_LOSS", "UNAUTHENTICATED"};
  const int code = static_cast<int>(s.error_code());
  std::cerr << "gonogo: " << (code >= 0 && code <= 16 ? kNames[code] : "ERROR") << ": "
            << s.error_message() << "\n";
  return 3;
}

const char* StateName(v1::JobState s) {
  switch (s) {
    case v1::JOB_STATE_QUEUED: return "QUEUED";
    case v1::JOB_STATE_RUNNING: return "RUNNING";
    case v1::JOB_STATE_DONE: return "DONE";
    case v1::JOB_STATE_FAILED: return "FAILED";
    case v1::JOB_STATE_CANCELLED: return "CANCELLED";
    default: return "UNKNOWN";
  }
}


// Progress on stderr: a redrawn bar on a terminal, a line per 10 % (or new phase) otherwise.
class ProgressBar {
 public:
  ProgressBar() : tty_(isatty(STDERR_FILENO)) {}
  void Show(const v1::JobStatus& s) {
    const int percent = static_cast<int>(std::floor(100 * s.fraction_done()));
    std::ostringstream line;
    const int filled = percent * 30 / 100;
    line << "[" << std::string(filled, '#') << std::string(30 - filled, '-') << "] "
         << std::setw(3) << percent << "%  tasks " << s.tasks_done() << "/" << s.tasks_total()
         << "  cache hits " << s.cache_hits() << "  similar " << s.similarity_hits() << "  "
         << StateName(s.state()) << ": "
         << s.message();
    if (tty_) {
      std::cerr << "\r\033[K" << line.str() << std::flush;
    } else if (percent / 10 != last_decile_ || s.state() != last_state_) {
      std::cerr << line.str() << "\n";
    }
    last_decile_ = percent / 10;
    last_state_ = s.state();
  }
  void Done() {
    if (tty_) std::cerr << "\n";
  }

 private:
  bool tty_;
  int last_decile_ = -1;
  v1::JobState last_state_ = v1::JOB_STATE_UNSPECIFIED;
};

class Client {
 public:
  explicit Client(const std::string& endpoint)
      : stub_(v1::MobilityService::NewStub(
            grpc::CreateChannel(endpoint, grpc::InsecureChannelCredentials()))) {}

  // Follows the job until it ends; returns its final status.
  grpc::Status Watch(const std::string& id, v1::JobStatus* last) {
    ProgressBar bar;
    grpc::ClientContext ctx;
    v1::WatchJobRequest req;
    req.set_job_id(id);
    auto reader = stub_->WatchJob(&ctx, req);
    v1::JobStatus s;
    while (reader->Read(&s)) {
      bar.Show(s);
      *last = s;
    }
    bar.Done();
    return reader->Finish();
  }

  grpc::Status Download(const std::string& id, const std::string& out_dir,
                        std::vector<std::string>* written) {
    fs::create_directories(out_dir);
    grpc::ClientContext ctx;
    v1::DownloadResultRequest req;
    req.set_job_id(id);
    auto reader = stub_->DownloadResult(&ctx, req);
    v1::ResultChunk chunk;
    std::ofstream out;
    std::string current;
    while (reader->Read(&chunk)) {
      if (chunk.product() != current) {
        out.close();
        current = chunk.product();
        // Only plain file names are accepted from the server.
        if (current.empty() || current.find('/') != std::string::npos || current[0] == '.') {
          return {grpc::StatusCode::INTERNAL, "server sent a bad product name"};
        }
        out.open(fs::path(out_dir) / current, std::ios::binary | std::ios::trunc);
        written->push_back((fs::path(out_dir) / current).string());
      }
      out.write(chunk.data().data(), static_cast<std::streamsize>(chunk.data().size()));
    }
    return reader->Finish();
  }

  v1::MobilityService::Stub& stub() { return *stub_; }

 private:
  std::unique_ptr<v1::MobilityService::Stub> stub_;
};

int Map(Client& client, const Args& a) {
  v1::MapRequest request;
  request.set_name(a.Get("name", "map " + fs::path(a.Need("cone-index")).stem().string()));
  request.set_tier(a.Need("tier"));
  request.set_disable_similarity(a.Has("no-similarity"));
  *request.mutable_vehicle() = ReadJson<v1::Vehicle>(a.Need("vehicle"), "vehicle file");
  if (a.Has("soil-table")) {
    *request.mutable_soil_table() = ReadJson<v1::SoilTable>(a.Get("soil-table"), "soil table");
  }
  v1::Criteria* c = request.mutable_criteria();
  c->set_passes(static_cast<uint32_t>(a.Number("passes", 0)));
  c->set_design_slip(a.Number("design-slip", 0));
  c->set_max_slip(a.Number("max-slip", 0));
  c->set_go_margin(a.Number("go-margin", 0));
  c->set_slip_step(a.Number("slip-step", 0));
  const std::string out_dir = a.Need("out");
  if (a.Has("slope") == a.Has("elevation")) {
    throw UsageError("give exactly one of --slope FILE or --elevation FILE");
  }
  std::vector<std::pair<v1::RasterRole, std::string>> rasters = {
      {v1::RASTER_ROLE_CONE_INDEX, a.Need("cone-index")}};
  if (a.Has("slope")) rasters.emplace_back(v1::RASTER_ROLE_SLOPE, a.Get("slope"));
  if (a.Has("elevation")) rasters.emplace_back(v1::RASTER_ROLE_ELEVATION, a.Get("elevation"));
  if (a.Has("soil-class")) rasters.emplace_back(v1::RASTER_ROLE_SOIL_CLASS, a.Get("soil-class"));
  std::vector<std::pair<v1::RasterRole, std::string>> contents;
  for (const auto& [role, path] : rasters) contents.emplace_back(role, ReadFile(path, "raster"));

  grpc::ClientContext ctx;
  v1::Job job;
  auto writer = client.stub().SubmitMap(&ctx, &job);
  v1::SubmitMapRequest first;
  *first.mutable_request() = request;
  bool ok = writer->Write(first);
  for (const auto& [role, bytes] : contents) {
    for (size_t off = 0; ok && off < bytes.size(); off += kChunkBytes) {
      v1::SubmitMapRequest m;
      m.mutable_chunk()->set_role(role);
      m.mutable_chunk()->set_data(bytes.substr(off, kChunkBytes));
      ok = writer->Write(m);
    }
  }
  writer->WritesDone();
  const grpc::Status submitted = writer->Finish();
  if (!submitted.ok()) return Fail(submitted);
  std::cerr << "submitted " << job.job_id() << " (" << request.tier() << ", "
            << request.vehicle().name() << ")\n";
  std::cout << job.job_id() << std::endl;
  if (a.Has("no-wait")) return 0;

  v1::JobStatus last;
  const grpc::Status watched = client.Watch(job.job_id(), &last);
  if (!watched.ok()) return Fail(watched);
  if (last.state() != v1::JOB_STATE_DONE) {
    std::cerr << "gonogo: job " << job.job_id() << " " << StateName(last.state()) << ": "
              << last.message() << "\n";
    return 1;
  }
  std::vector<std::string> written;
  const grpc::Status fetched = client.Download(job.job_id(), out_dir, &written);
  if (!fetched.ok()) return Fail(fetched);
  for (const auto& f : written) std::cerr << "wrote " << f << "\n";
  return 0;
}

int Jobs(Client& client, const Args& a) {
  grpc::ClientContext ctx;
  v1::ListJobsRequest req;
  req.set_limit(static_cast<uint32_t>(a.Number("limit", 50)));
  v1::ListJobsResponse resp;
  const grpc::Status s = client.stub().ListJobs(&ctx, req, &resp);
  if (!s.ok()) return Fail(s);
  std::cout << std::left << std::setw(18) << "JOB" << std::setw(11) << "STATE" << std::setw(11)
            << "TIER" << std::setw(7) << "DONE" << std::setw(13) << "TASKS" << "NAME / MESSAGE\n";
  for (const auto& j : resp.jobs()) {
    std::ostringstream tasks;
    tasks << j.status().tasks_done() << "/" << j.status().tasks_total();
    std::cout << std::left << std::setw(18) << j.job_id() << std::setw(11)
              << StateName(j.status().state()) << std::setw(11) << j.tier() << std::setw(7)
              << (std::to_string(static_cast<int>(100 * j.status().fraction_done())) + "%")
              << std::setw(13) << tasks.str() << j.name() << " / " << j.status().message() << "\n";
  }
  return 0;
}

int Tiers(Client& client, const Args&) {
  grpc::ClientContext ctx;
  v1::ListTiersResponse resp;
  const grpc::Status s = client.stub().ListTiers(&ctx, v1::ListTiersRequest{}, &resp);
  if (!s.ok()) return Fail(s);
  for (const auto& t : resp.tiers()) {
    std::cout << t.name() << " (" << t.version() << ")\n"
              << "  model:  " << t.summary() << "\n"
              << "  reads:  " << t.reads() << "\n"
              << "  needs:  " << t.ranks() << (t.ranks() == 1 ? " rank, " : " ranks, ")
              << t.threads() << (t.threads() == 1 ? " thread" : " threads") << " per curve\n"
              << "  cost:   " << t.typical_cost() << "\n";
  }
  return 0;
}

int Watch(Client& client, const Args& a) {
  if (a.positional.size() != 1) throw UsageError("watch needs one job id");
  v1::JobStatus last;
  const grpc::Status s = client.Watch(a.positional[0], &last);
  if (!s.ok()) return Fail(s);
  std::cout << a.positional[0] << " " << StateName(last.state()) << ": " << last.message() << "\n";
  return last.state() == v1::JOB_STATE_DONE ? 0 : 1;
}

int Cancel(Client& client, const Args& a) {
  if (a.positional.size() != 1) throw UsageError("cancel needs one job id");
  grpc::ClientContext ctx;
  v1::CancelJobRequest req;
  req.set_job_id(a.positional[0]);
  v1::Job job;
  const grpc::Status s = client.stub().CancelJob(&ctx, req, &job);
  if (!s.ok()) return Fail(s);
  std::cout << job.job_id() << " " << StateName(job.status().state()) << ": "
            << job.status().message() << "\n";
  return 0;
}

int Download(Client& client, const Args& a) {
  if (a.positional.size() != 1) throw UsageError("download needs one job id");
  std::vector<std::string> written;
  const grpc::Status s = client.Download(a.positional[0], a.Need("out"), &written);
  if (!s.ok()) return Fail(s);
  for (const auto& f : written) std::cout << f << "\n";
  return 0;
}

// "n=0.7,kc=5270,kphi=1515040,c=1300,phi_deg=31.1,K=0.0115" -> parameters; every key exactly once.
v1::BekkerParameters ParseBekker(const std::string& text) {
  std::map<std::string, double> values;
  std::istringstream items(text);
  for (std::string item; std::getline(items, item, ',');) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos) throw UsageError("--bekker: '" + item + "' is not KEY=VALUE");
    const std::string key = item.substr(0, eq);
    try {
      size_t used = 0;
      values[key] = std::stod(item.substr(eq + 1), &used);
      if (used != item.size() - eq - 1) throw std::invalid_argument("");
    } catch (const std::logic_error&) {
      throw UsageError("--bekker: " + key + " needs a number");
    }
  }
  const std::vector<std::string> keys = {"n", "kc", "kphi", "c", "phi_deg", "K"};
  for (const auto& k : keys) {
    if (!values.count(k)) throw UsageError("--bekker: " + k + "= is missing");
  }
  if (values.size() != keys.size()) {
    throw UsageError("--bekker: only n, kc, kphi, c, phi_deg and K are known");
  }
  v1::BekkerParameters p;
  p.set_n(values["n"]);
  p.set_kc(values["kc"]);
  p.set_kphi(values["kphi"]);
  p.set_cohesion_pa(values["c"]);
  p.set_friction_angle_deg(values["phi_deg"]);
  p.set_shear_deformation_m(values["K"]);
  return p;
}

// The soil options shared by `curve` and `scalability`.
v1::SoilState SoilFromArgs(const Args& a) {
  if (!a.Has("cone-index") && !a.Has("soil") && !a.Has("bekker")) {
    throw UsageError("give the soil: --cone-index KPA, --soil NAME or --bekker ...");
  }
  v1::SoilState soil;
  if (a.Has("cone-index")) soil.set_cone_index_pa(a.Number("cone-index", 0) * 1000.0);
  soil.set_soil_name(a.Get("soil"));
  if (a.Has("bekker")) *soil.mutable_bekker() = ParseBekker(a.Get("bekker"));
  return soil;
}

// The wheel options shared by `curve` and `scalability`: a vehicle's axle, or the wheel itself.
void WheelFromArgs(const Args& a, v1::Tyre* tyre, double* wheel_load_n) {
  if (a.Has("vehicle")) {
    const auto vehicle = ReadJson<v1::Vehicle>(a.Get("vehicle"), "vehicle file");
    const int axle = static_cast<int>(a.Number("axle", 1)) - 1;
    if (axle < 0 || axle >= vehicle.axles_size()) {
      throw UsageError("--axle must lie in 1.." + std::to_string(vehicle.axles_size()));
    }
    const v1::Axle& ax = vehicle.axles(axle);
    double fraction = ax.load_fraction();
    if (fraction == 0 && vehicle.wheelbase_m() > 0 && vehicle.axles_size() == 2) {
      const double rear = vehicle.cg_behind_front_axle_m() / vehicle.wheelbase_m();
      fraction = axle == 0 ? 1 - rear : rear;
    }
    *tyre = ax.tyre();
    *wheel_load_n = vehicle.mass_kg() * 9.80665 * fraction / std::max(1u, ax.wheels());
    return;
  }
  for (const char* k : {"wheel-diameter", "wheel-width", "wheel-load"}) {
    if (!a.Has(k)) throw UsageError(std::string("--") + k + " is required without --vehicle");
  }
  tyre->set_diameter_m(a.Number("wheel-diameter", NAN));
  tyre->set_width_m(a.Number("wheel-width", NAN));
  // A rigid wheel has no section height: a quarter of the diameter stands in (it only enters
  // the empirical tier's deflection ratio, which is 0 for a rigid wheel).
  tyre->set_section_height_m(a.Number("section-height", 0.25 * tyre->diameter_m()));
  tyre->set_deflection_m(a.Number("deflection", 0));
  tyre->set_rolling_radius_m(a.Number("rolling-radius", 0));
  tyre->set_inflation_pressure_pa(a.Number("inflation-pressure-kpa", 0) * 1000.0);
  *wheel_load_n = a.Number("wheel-load", NAN);
}

int Curve(Client& client, const Args& a) {
  v1::GetTractionCurveRequest req;
  req.set_tier(a.Need("tier"));
  *req.mutable_soil() = SoilFromArgs(a);
  req.set_slip_step(a.Number("slip-step", 0));
  req.set_disable_similarity(a.Has("no-similarity"));
  double load = 0;
  WheelFromArgs(a, req.mutable_tyre(), &load);
  req.set_wheel_load_n(load);
  grpc::ClientContext ctx;
  v1::TractionCurve curve;
  const grpc::Status s = client.stub().GetTractionCurve(&ctx, req, &curve);
  if (!s.ok()) return Fail(s);
  const auto& p = curve.provenance();
  if (a.Has("csv")) {
    std::cout << "slip,drawbar_pull_n,torque_nm,sinkage_m,tractive_efficiency,gross_traction_n,"
                 "motion_resistance_n\n";
    for (const auto& pt : curve.points()) {
      std::cout << pt.slip() << "," << pt.drawbar_pull_n() << "," << pt.torque_nm() << ","
                << pt.sinkage_m() << "," << pt.tractive_efficiency() << ","
                << pt.gross_traction_n() << "," << pt.motion_resistance_n() << "\n";
    }
  } else {
    std::cout << "tier " << p.tier() << " (" << p.tier_version() << "), wheel load "
              << curve.wheel_load_n() << " N, ";
    if (!curve.soil().soil_name().empty()) std::cout << "soil " << curve.soil().soil_name() << ", ";
    if (curve.soil().has_bekker()) std::cout << "explicit Bekker parameters, ";
    if (curve.soil().cone_index_pa() > 0) {
      std::cout << "cone index " << curve.soil().cone_index_pa() / 1000 << " kPa, ";
    }
    std::cout << (p.cache_hit() ? "from the cache" : "computed") << " by " << p.computed_by()
              << "\n";
    if (p.similarity_hit()) {
      const auto& r = p.reliability();
      std::cout << "similarity hit: scaled from a tyre " << 1 / p.similarity_scale_ratio()
                << " times this size; seed 001 measured at scale " << r.reference_scale()
                << " on " << r.reference_soil() << ": " << r.drawbar_pull_pct() << " % (D/W), "
                << r.gross_traction_pct() << " % (T/rW), " << r.efficiency_pct()
                << " % (efficiency) of points inside the full-scale band\n";
    }
    std::cout << std::right << std::setw(6) << "slip" << std::setw(14) << "drawbar_N"
              << std::setw(14) << "torque_Nm" << std::setw(12) << "sinkage_m" << std::setw(12)
              << "efficiency" << "\n";
    for (const auto& pt : curve.points()) {
      std::cout << std::fixed << std::setprecision(3) << std::setw(6) << pt.slip()
                << std::setprecision(1) << std::setw(14) << pt.drawbar_pull_n() << std::setw(14)
                << pt.torque_nm() << std::setprecision(4) << std::setw(12) << pt.sinkage_m()
                << std::setprecision(3) << std::setw(12) << pt.tractive_efficiency() << "\n";
    }
  }
  std::cerr << (p.similarity_hit() ? "source cache key: " : "cache key: ") << p.cache_key()
            << "\n";
  return 0;
}

int Scalability(Client& client, const Args& a) {
  v1::ScalabilityRequest req;
  req.set_tier(a.Need("tier"));
  *req.mutable_soil() = SoilFromArgs(a);
  double load = 0;
  WheelFromArgs(a, req.mutable_tyre(), &load);
  req.set_wheel_load_n(load);
  req.set_slip_step(a.Number("slip-step", 0));
  std::istringstream scales(a.Get("scales", "1,0.7,0.5,0.25"));
  for (std::string item; std::getline(scales, item, ',');) {
    try {
      req.add_scales(std::stod(item));
    } catch (const std::logic_error&) {
      throw UsageError("--scales needs numbers separated by commas, got '" + item + "'");
    }
  }
  const fs::path out = a.Need("out");
  grpc::ClientContext ctx;
  v1::ScalabilityReport report;
  const grpc::Status s = client.stub().RunScalability(&ctx, req, &report);
  if (!s.ok()) return Fail(s);
  fs::create_directories(out);
  std::ofstream(out / "scalability.png", std::ios::binary) << report.plot_png();
  std::ofstream curves(out / "scalability_curves.csv");
  curves << "scale,slip,drawbar_pull_coefficient,gross_traction_coefficient,tractive_efficiency,"
            "drawbar_pull_n,torque_nm,sinkage_m,wheel_load_n,rolling_radius_m\n";
  std::ofstream summary(out / "scalability_summary.csv");
  summary << "scale,diameter_m,width_m,wheel_load_n,drawbar_pull_inside_pct,"
             "gross_traction_inside_pct,efficiency_inside_pct,seed_soil,seed_scale,"
             "seed_drawbar_pull_pct,seed_gross_traction_pct,seed_efficiency_pct,immobile\n";
  std::cout << "band (one SD of the full-scale coefficient): D/W " << report.band_drawbar_pull()
            << ", T/(rW) " << report.band_gross_traction() << ", efficiency "
            << report.band_efficiency() << "\n";
  std::cout << std::left << std::setw(7) << "scale" << std::setw(10) << "d_m" << std::setw(11)
            << "W_N" << std::setw(22) << "inside: D/W  T/rW  eff" << "  seed 001 measured\n";
  for (const auto& row : report.rows()) {
    const double r = row.tyre().rolling_radius_m() > 0
                         ? row.tyre().rolling_radius_m()
                         : row.tyre().diameter_m() / 2 - row.tyre().deflection_m();
    for (const auto& p : row.points()) {
      curves << row.scale() << "," << p.slip() << "," << p.drawbar_pull_n() / row.wheel_load_n()
             << "," << p.torque_nm() / (r * row.wheel_load_n()) << "," << p.tractive_efficiency()
             << "," << p.drawbar_pull_n() << "," << p.torque_nm() << "," << p.sinkage_m() << ","
             << row.wheel_load_n() << "," << r << "\n";
    }
    const auto& m = row.seed_measured();
    summary << row.scale() << "," << row.tyre().diameter_m() << "," << row.tyre().width_m() << ","
            << row.wheel_load_n() << "," << row.drawbar_pull_inside_pct() << ","
            << row.gross_traction_inside_pct() << "," << row.efficiency_inside_pct() << ","
            << m.reference_soil() << "," << m.reference_scale() << "," << m.drawbar_pull_pct()
            << "," << m.gross_traction_pct() << "," << m.efficiency_pct() << ","
            << (row.immobile_reason().empty() ? "" : "yes") << "\n";
    std::ostringstream inside, seed;
    inside << std::fixed << std::setprecision(1) << row.drawbar_pull_inside_pct() << "  "
           << row.gross_traction_inside_pct() << "  " << row.efficiency_inside_pct();
    if (!row.immobile_reason().empty()) {
      inside.str("cannot carry");
      std::cerr << "scale " << row.scale() << ": " << row.immobile_reason() << "\n";
    }
    if (row.has_seed_measured()) {
      seed << m.reference_soil() << " " << m.reference_scale() << ": " << m.drawbar_pull_pct()
           << "  " << m.gross_traction_pct() << "  " << m.efficiency_pct();
    }
    std::cout << std::left << std::setw(7) << row.scale() << std::setw(10)
              << row.tyre().diameter_m() << std::setw(11) << row.wheel_load_n() << std::setw(22)
              << inside.str() << "  " << seed.str() << "\n";
  }
  std::cerr << "wrote " << (out / "scalability.png").string() << ", "
            << (out / "scalability_curves.csv").string() << ", "
            << (out / "scalability_summary.csv").string() << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string server = std::getenv("GONOGO_SERVER") ? std::getenv("GONOGO_SERVER") : "127.0.0.1:50051";
  try {
    while (!args.empty() && args[0].rfind("--", 0) == 0) {
      if (args[0] == "--help" || args[0] == "-h") {
        std::cout << kUsage;
        return 0;
      }
      if (args[0] != "--server" || args.size() < 2) throw UsageError("unknown option " + args[0]);
      server = args[1];
      args.erase(args.begin(), args.begin() + 2);
    }
    if (args.empty()) throw UsageError("no command");
    if (!server.empty() && server[0] == '@') {
      std::string endpoint = ReadFile(server.substr(1), "endpoint file");
      endpoint.erase(endpoint.find_last_not_of(" \n\r\t") + 1);
      server = endpoint;
    }
    const std::string command = args[0];
    const Args a = ParseArgs({args.begin() + 1, args.end()}, {"csv", "no-wait", "no-similarity"});
    Client client(server);
    if (command == "map") return Map(client, a);
    if (command == "jobs") return Jobs(client, a);
    if (command == "tiers") return Tiers(client, a);
    if (command == "watch") return Watch(client, a);
    if (command == "cancel") return Cancel(client, a);
    if (command == "download") return Download(client, a);
    if (command == "curve") return Curve(client, a);
    if (command == "scalability") return Scalability(client, a);
    throw UsageError("unknown command '" + command + "'");
  } catch (const UsageError& e) {
    std::cerr << "gonogo: " << e.what() << "\n" << kUsage;
    return 2;
  }
}
