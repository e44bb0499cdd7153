#include "solvers/tiers/surrogate_registry.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "solvers/common/errors.h"

namespace gonogo::tiers {

namespace fs = std::filesystem;

namespace {

constexpr char kRecordFile[] = "model.txt";
constexpr char kRecordHeader[] = "# gonogo surrogate model 1";
// An id's stem ("<soil>-<architecture>") at most: with "-<n>" after it, up to 7 digits, an id
// stays within ValidateModelId's 64 characters.
constexpr std::size_t kIdStemChars = 56;

// `text` with every `from` replaced by `to`.
std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos;
       at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

// The short form of an architecture's name (MlpArchitecture::Describe), for an id that would
// otherwise be cut: "mlp-128x128-tanh-anchored-pressure-scaled-3000pa-carrying-coordination_number"
// is "mlp-128x128-anchored-ps3000pa-cn". Every network is tanh; the hybrid is "-hy"; the carried
// variables by their initials (fabric_xy: fxy).
std::string ShortArchitecture(std::string architecture) {
  for (const auto& [from, to] : {std::pair<const char*, const char*>{"-tanh", ""},
                                 {"-hybrid", "-hy"},
                                 {"-previous-direction", "-pd"},
                                 {"-pressure-scaled-", "-ps"},
                                 {"-carrying-", "-"},
                                 {"coordination_number", "cn"},
                                 {"solid_fraction", "sf"},
                                 {"fabric_", "f"}}) {
    architecture = Replaced(std::move(architecture), from, to);
  }
  return architecture;
}

// "<soil>-<architecture>" in an id's characters (any other is '-').
std::string IdCharacters(const std::string& text) {
  std::string id;
  for (char c : text) {
    const bool kept = std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_';
    id += kept ? c : '-';
  }
  return id;
}

std::string Number(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

// One "key = value" per line; held-out errors as "held_out = <error> <path>", each followed by its
// differences on other packings as "held_out_packing = <seed> <difference> <path>".
std::string RecordText(const RegisteredSurrogate& r) {
  std::ostringstream out;
  out << kRecordHeader << "\n"
      << "id = " << r.id << "\n"
      << "soil_name = " << r.soil_name << "\n"
      << "soil_parameters = " << r.soil_parameters << "\n"
      << "fe_de_preset = " << r.fe_de_preset << "\n"
      << "architecture = " << r.architecture << "\n"
      << "members = " << r.members << "\n"
      << "data_hash = " << r.data_hash << "\n"
      << "samples = " << r.samples << "\n"
      << "fallback_paths = " << r.fallback_paths << "\n"
      << "fallback_paths_share = " << Number(r.fallback_paths_share) << "\n"
      << "walk_share = " << Number(r.walk_share) << "\n"
      << "distance_threshold = " << Number(r.distance_threshold) << "\n"
      << "spread_threshold = " << Number(r.spread_threshold) << "\n"
      << "tensile_limit_pa = " << Number(r.tensile_limit_pa) << "\n"
      << "least_principal_ratio = " << Number(r.least_principal_ratio) << "\n"
      << "worst_held_out_error = " << Number(r.worst_held_out_error) << "\n"
      << "training_seconds = " << Number(r.training_seconds) << "\n"
      << "training = " << r.training << "\n"
      << "from_model = " << r.from_model << "\n"
      << "code_version = " << r.code_version << "\n"
      << "created_unix_ms = " << r.created_unix_ms << "\n";
  for (const HeldOutResult& result : r.held_out) {
    out << "held_out = " << Number(result.replay_error) << " " << result.path << "\n";
    for (const PackingDifference& packing : result.packings) {
      out << "held_out_packing = " << packing.packing_seed << " " << Number(packing.difference)
          << " " << result.path << "\n";
    }
  }
  return out.str();
}

// nullopt for a directory that is not a model (no record, or not one this code reads).
std::optional<RegisteredSurrogate> ReadRecord(const fs::path& directory) {
  std::ifstream in(directory / kRecordFile);
  std::string line;
  if (!in || !std::getline(in, line) || line != kRecordHeader) return std::nullopt;
  std::map<std::string, std::string> values;
  RegisteredSurrogate r;
  try {
    while (std::getline(in, line)) {
      const std::size_t equals = line.find(" = ");
      if (equals == std::string::npos) return std::nullopt;
      const std::string key = line.substr(0, equals), value = line.substr(equals + 3);
      if (key == "held_out") {
        const std::size_t space = value.find(' ');
        if (space == std::string::npos) return std::nullopt;
        r.held_out.push_back({value.substr(space + 1), std::stod(value.substr(0, space)), {}});
      } else if (key == "held_out_packing") {  // of the held-out path before it
        std::istringstream fields(value);
        PackingDifference packing;
        std::string path;
        if (!(fields >> packing.packing_seed >> packing.difference) || r.held_out.empty()) {
          return std::nullopt;
        }
        std::getline(fields >> std::ws, path);
        if (path != r.held_out.back().path) return std::nullopt;
        r.held_out.back().packings.push_back(packing);
      } else {
        values[key] = value;
      }
    }
    r.id = values.at("id");
    r.soil_name = values.at("soil_name");
    r.soil_parameters = values.at("soil_parameters");
    r.fe_de_preset = values.at("fe_de_preset");
    r.architecture = values.at("architecture");
    r.members = std::stoi(values.at("members"));
    r.data_hash = values.at("data_hash");
    r.samples = std::stoll(values.at("samples"));
    if (values.count("fallback_paths") != 0) {  // absent before they were kept: none
      r.fallback_paths = std::stoi(values.at("fallback_paths"));
      r.fallback_paths_share = std::stod(values.at("fallback_paths_share"));
    }
    if (values.count("walk_share") != 0) r.walk_share = std::stod(values.at("walk_share"));
    r.distance_threshold = std::stod(values.at("distance_threshold"));
    r.spread_threshold = std::stod(values.at("spread_threshold"));
    if (values.count("tensile_limit_pa") != 0) {  // absent before the cap: none
      r.tensile_limit_pa = std::stod(values.at("tensile_limit_pa"));
    }
    if (values.count("least_principal_ratio") != 0) {  // absent before the cone: none
      r.least_principal_ratio = std::stod(values.at("least_principal_ratio"));
    }
    r.worst_held_out_error = std::stod(values.at("worst_held_out_error"));
    r.training_seconds = std::stod(values.at("training_seconds"));
    if (values.count("training") != 0) r.training = values.at("training");  // absent before: ""
    r.from_model = values.at("from_model");
    r.code_version = values.at("code_version");
    r.created_unix_ms = std::stoll(values.at("created_unix_ms"));
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (r.id != directory.filename().string()) return std::nullopt;
  r.directory = directory.string();
  return r;
}

}  // namespace

std::string TrainingText(const ann::TrainingOptions& options) {
  std::ostringstream out;  // six significant digits: a record a person reads
  out << "epochs=" << options.epochs << " batch_size=" << options.batch_size
      << " learning_rate=" << options.learning_rate << " seed=" << options.seed
      << " path_stress_weighting=" << options.path_stress_weighting
      << " rollout_steps=" << options.rollout_steps;
  if (options.rollout_steps > 0) out << " rollout_weight=" << options.rollout_weight;
  if (options.stress_noise > 0) {
    out << " stress_noise=" << options.stress_noise
        << " noise_correction=" << options.noise_correction;
  }
  out << " weighted_histories="
      << std::count_if(options.history_weights.begin(), options.history_weights.end(),
                       [](double weight) { return weight != 1.0; });
  return out.str();
}

void ValidateModelId(const std::string& id, const std::string& field) {
  Require(!id.empty() && id.size() <= 64, field, "must be 1 to 64 characters");
  Require(id.front() != '.', field, "must not start with '.'");
  for (char c : id) {
    Require(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.',
            field, "must be letters, digits, '-', '_' and '.'");
  }
}

SurrogateRegistry::SurrogateRegistry(std::string root) : root_(std::move(root)) {
  Require(!root_.empty(), "models_dir", "is required");
}

std::optional<RegisteredSurrogate> SurrogateRegistry::Describe(const std::string& id) const {
  try {
    ValidateModelId(id, "model");
  } catch (const InputError&) {
    return std::nullopt;  // no such model can exist
  }
  return ReadRecord(fs::path(root_) / id);
}

std::optional<SurrogateModelRecord> SurrogateRegistry::Find(const std::string& id) const {
  std::optional<RegisteredSurrogate> found = Describe(id);
  if (!found) return std::nullopt;
  return static_cast<SurrogateModelRecord>(*found);
}

std::vector<RegisteredSurrogate> SurrogateRegistry::List(const std::string& soil_name) const {
  std::vector<RegisteredSurrogate> models;
  std::error_code error;
  if (!fs::is_directory(root_, error)) return models;
  for (const fs::directory_entry& entry : fs::directory_iterator(root_, error)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name.front() == '.' || !entry.is_directory(error)) continue;
    std::optional<RegisteredSurrogate> model = ReadRecord(entry.path());
    if (model && (soil_name.empty() || model->soil_name == soil_name)) {
      models.push_back(std::move(*model));
    }
  }
  std::sort(models.begin(), models.end(),
            [](const RegisteredSurrogate& a, const RegisteredSurrogate& b) {
              return a.created_unix_ms != b.created_unix_ms ? a.created_unix_ms > b.created_unix_ms
                                                            : a.id < b.id;
            });
  return models;
}

double WorstErrorBeyondFloor(const RegisteredSurrogate& model) {
  if (model.held_out.empty()) return model.worst_held_out_error;
  double worst = 0;
  for (const HeldOutResult& path : model.held_out) {
    worst = std::max(worst, path.replay_error - PackingFloor(path.packings));
  }
  return worst;
}

std::optional<SurrogateModelRecord> SurrogateRegistry::Best(const std::string& soil_parameters,
                                                            const std::string& fe_de_preset) const {
  std::optional<RegisteredSurrogate> best;
  double best_beyond_floor = 0;
  for (RegisteredSurrogate& model : List()) {  // newest first: ties go to the newest
    if (model.soil_parameters != soil_parameters || model.fe_de_preset != fe_de_preset) continue;
    const double beyond_floor = WorstErrorBeyondFloor(model);
    if (!best || beyond_floor < best_beyond_floor ||
        (beyond_floor == best_beyond_floor &&
         model.worst_held_out_error < best->worst_held_out_error)) {
      best_beyond_floor = beyond_floor;
      best = std::move(model);
    }
  }
  if (!best) return std::nullopt;
  return static_cast<SurrogateModelRecord>(*best);
}

std::string SurrogateRegistry::NewId(const std::string& soil_name,
                                     const std::string& architecture) const {
  std::string stem = IdCharacters(soil_name + "-" + architecture);
  if (stem.size() > kIdStemChars) {
    stem = IdCharacters(soil_name + "-" + ShortArchitecture(architecture));
  }
  if (stem.size() > kIdStemChars) {  // still too long: cut after a whole word
    const std::size_t last_dash = stem.rfind('-', kIdStemChars);
    stem.resize(last_dash != std::string::npos && last_dash > 0 ? last_dash : kIdStemChars);
  }
  if (stem.empty() || stem.front() == '-') stem = "model" + stem;
  for (int n = 1;; ++n) {
    const std::string id = stem + "-" + std::to_string(n);
    if (!fs::exists(fs::path(root_) / id)) return id;
  }
}

RegisteredSurrogate SurrogateRegistry::Register(RegisteredSurrogate record,
                                                const ann::SurrogateEnsemble& ensemble) const {
  ValidateModelId(record.id, "model.id");
  fs::create_directories(root_);
  const fs::path final_path = fs::path(root_) / record.id;
  Require(!fs::exists(final_path), "model.id", "a model '" + record.id + "' is registered already");
  const fs::path staging =
      fs::path(root_) / ("." + record.id + ".registering." + std::to_string(::getpid()));
  fs::remove_all(staging);
  ensemble.Save(staging.string());
  record.directory = final_path.string();
  {
    std::ofstream out(staging / kRecordFile, std::ios::trunc);
    out << RecordText(record);
    out.close();
    if (!out) throw std::runtime_error("cannot write " + (staging / kRecordFile).string());
  }
  std::error_code error;
  fs::rename(staging, final_path, error);  // atomic; fails when the id was taken meanwhile
  if (error) {
    fs::remove_all(staging);
    throw InputError("model.id", "a model '" + record.id + "' is registered already");
  }
  return record;
}

int SurrogateRegistry::CollectAbandoned() const {
  int removed = 0;
  std::error_code error;
  if (!fs::is_directory(root_, error)) return 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(root_, error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind('.', 0) == 0 && name.find(".registering.") != std::string::npos) {
      fs::remove_all(entry.path(), error);
      ++removed;
    }
  }
  return removed;
}

}  // namespace gonogo::tiers
