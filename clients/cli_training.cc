// gonogo models | train | dataset: the fe-ann tier's surrogate models and the RVE histories they
// are trained on.
//   gonogo models [--soil NAME]
//   gonogo train --soil NAME [--hidden 64x64] [--from MODEL] [--epochs N] [--rig-load-n N] ...
//                [--no-wait]
//   gonogo dataset [--soil NAME]
//   gonogo dataset export DATASET --out DIR [--format csv|npy] [--role training|held-out]
// and the surrogate options of `gonogo curve` and `gonogo map` (AddSurrogateOptions).
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "clients/cli_commands.h"

namespace gonogo::cli {
namespace {

// A fraction as a percentage with one decimal ("3.2 %").
std::string Percent(double fraction) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1) << 100 * fraction << " %";
  return out.str();
}

// What carried the loss beyond each step's share, for the model's data line: " (the walks 60.0 %
// of the recipe's loss; 37 fallback paths, 20.0 % of the loss)", "" when nothing was weighed.
std::string DataShares(const v1::SurrogateModel& m) {
  std::vector<std::string> parts;
  if (m.walk_share() > 0) {
    parts.push_back("the walks " + Percent(m.walk_share()) + " of the recipe's loss");
  }
  if (m.fallback_paths() > 0) {
    parts.push_back(std::to_string(m.fallback_paths()) + " fallback paths, " +
                    Percent(m.fallback_paths_share()) + " of the loss");
  }
  std::string text;
  for (const std::string& part : parts) text += (text.empty() ? " (" : "; ") + part;
  return text.empty() ? text : text + ")";
}

void PrintModel(const v1::SurrogateModel& m) {
  std::cout << m.id() << "\n"
            << "  soil:      " << (m.soil_name().empty() ? "(explicit parameters)" : m.soil_name())
            << ", RVEs of the " << m.fe_de_preset() << " fe-de configuration\n"
            << "  network:   " << m.architecture() << ", " << m.members() << " members"
            << (m.from_model().empty() ? "" : ", fine-tuned from " + m.from_model()) << "\n"
            << "  data:      " << m.samples() << " steps" << DataShares(m) << ", hash "
            << m.data_hash() << ", trained in " << FormatNumber(m.training_seconds()) << " s\n"
            << "  training:  " << (m.training().empty() ? "(not recorded)" : m.training()) << "\n"
            << "  envelope:  distance " << FormatNumber(m.distance_threshold()) << ", spread "
            << FormatNumber(m.spread_threshold()) << ", principal stresses capped at "
            << (std::isfinite(m.tensile_limit_pa()) ? FormatNumber(m.tensile_limit_pa()) + " Pa"
                                                    : std::string("nothing (an older model)"))
            << (m.least_principal_ratio() > 0
                    ? ", within the cone min/max principal compression >= " +
                          FormatNumber(m.least_principal_ratio())
                    : std::string())
            << "\n"
            << "  held out:  worst " << Percent(m.worst_held_out_error());
  for (const auto& h : m.held_out()) {
    std::cout << "; " << h.path() << " " << Percent(h.replay_error());
    if (h.packings().empty()) continue;
    // The floor under it: the same path on the RVE's other packings.
    const auto [least, most] = std::minmax_element(
        h.packings().begin(), h.packings().end(),
        [](const auto& a, const auto& b) { return a.difference() < b.difference(); });
    std::cout << (h.packings_size() == 1 ? " (another packing " : " (other packings ")
              << Percent(least->difference());
    if (h.packings_size() > 1) {
      std::cout << " to " << Percent(most->difference()) << ", median " << Percent(h.floor());
    }
    std::cout << ")";
  }
  if (std::any_of(m.held_out().begin(), m.held_out().end(),
                  [](const auto& h) { return !h.packings().empty(); })) {
    // What the server ranks a soil's models by (its default: the least).
    std::cout << "\n  beyond the floors: " << Percent(m.worst_error_beyond_floor())
              << " (a path without packings counts whole)";
  }
  std::cout << "\n  made by:   gonogo " << m.code_version() << ", unix ms " << m.created_unix_ms()
            << "\n";
}

int RunModels(Client& client, const std::string& soil) {
  grpc::ClientContext ctx;
  v1::ListSurrogateModelsRequest request;
  request.set_soil_name(soil);
  v1::ListSurrogateModelsResponse resp;
  const grpc::Status s = client.stub().ListSurrogateModels(&ctx, request, &resp);
  if (!s.ok()) return Fail(s);
  if (resp.models().empty()) {
    std::cout << "no surrogate models" << (soil.empty() ? "" : " for " + soil)
              << " (gonogo train --soil NAME trains and registers one)\n";
    return kExitOk;
  }
  for (const auto& m : resp.models()) PrintModel(m);
  return kExitOk;
}

struct TrainOptions {
  v1::TrainSurrogateRequest request;
  std::string hidden;  // "64x64"
  std::vector<double> pressures_kpa;
  bool no_wait = false;
};

// "64x64" -> {64, 64}; UsageError naming --hidden otherwise.
std::vector<uint32_t> ParseWidths(const std::string& text) {
  std::vector<uint32_t> widths;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, 'x')) {
    try {
      size_t used = 0;
      const unsigned long width = std::stoul(item, &used);
      if (used != item.size() || width == 0) throw std::invalid_argument(item);
      widths.push_back(static_cast<uint32_t>(std::min(width, 1000000ul)));
    } catch (const std::exception&) {
      throw UsageError("--hidden: '" + text + "' is not layer widths such as 64x64");
    }
  }
  if (widths.empty()) throw UsageError("--hidden: '" + text + "' is not layer widths such as 64x64");
  return widths;
}

int RunTrain(Client& client, TrainOptions o) {
  if (!o.hidden.empty()) {
    for (uint32_t width : ParseWidths(o.hidden)) o.request.add_hidden_widths(width);
  }
  for (double p : o.pressures_kpa) o.request.add_pressures_kpa(p);
  v1::Job job;
  {
    grpc::ClientContext ctx;
    const grpc::Status s = client.stub().TrainSurrogate(&ctx, o.request, &job);
    if (!s.ok()) return Fail(s);
  }
  std::cerr << "training job " << job.job_id() << " submitted\n";
  if (o.no_wait) {
    std::cout << job.job_id() << "\n";
    return kExitOk;
  }
  v1::SurrogateModel model;
  if (const int rc = client.WaitForSummary(job.job_id(), "training job", &model); rc != kExitOk) {
    return rc;
  }
  std::cout << "registered ";
  PrintModel(model);
  return kExitOk;
}

int RunDatasets(Client& client, const std::string& soil) {
  grpc::ClientContext ctx;
  v1::ListDatasetsRequest request;
  request.set_soil_name(soil);
  v1::ListDatasetsResponse resp;
  const grpc::Status s = client.stub().ListDatasets(&ctx, request, &resp);
  if (!s.ok()) return Fail(s);
  if (resp.datasets().empty()) {
    std::cout << "no datasets" << (soil.empty() ? "" : " for " + soil)
              << " (gonogo train --soil NAME makes one)\n";
    return kExitOk;
  }
  for (const auto& d : resp.datasets()) {
    std::cout << d.dataset_id() << "\n"
              << "  soil:      " << d.soil_name() << ", RVEs of the " << d.fe_de_preset()
              << " fe-de configuration (" << d.rve_version() << ")\n"
              << "  histories: " << d.histories() << " (" << d.training_histories()
              << " training, " << d.held_out_histories() << " held out), " << d.steps()
              << " steps, " << d.bytes() << " bytes\n"
              << "  computed:  " << FormatNumber(d.compute_seconds()) << " s of RVE time, unix ms "
              << d.first_unix_ms() << " to " << d.last_unix_ms() << "\n";
  }
  return kExitOk;
}

struct ExportOptions {
  v1::ExportDatasetRequest request;
  std::string out_dir;
};

int RunExport(Client& client, const ExportOptions& o) {
  std::vector<std::string> written;
  const grpc::Status s = client.ExportDataset(o.request, o.out_dir, &written);
  if (!s.ok()) return Fail(s);
  for (const std::string& path : written) std::cout << path << "\n";
  return kExitOk;
}

}  // namespace

Command AddModelsCommand(CLI::App& parent) {
  auto soil = std::make_shared<std::string>();
  CLI::App* models = parent.add_subcommand(
      "models", "the fe-ann tier's surrogate models: soil, network, data, envelope, errors");
  models->add_option("--soil", *soil, "only this soil's models")->type_name("NAME");
  return {models, [soil](Client& client) { return RunModels(client, *soil); }};
}

Command AddTrainCommand(CLI::App& parent) {
  auto o = std::make_shared<TrainOptions>();
  v1::TrainSurrogateRequest& r = o->request;
  CLI::App* train = parent.add_subcommand(
      "train", "train and register an fe-ann surrogate of a soil's DE RVE (a job on the pool)");
  train->footer(
      "The RVE strain paths run on the server's worker pool and are kept in its data (gonogo "
      "dataset);\na later training on the same soil reuses them. Then each ensemble member is "
      "trained on the pool,\nmeasured on held-out paths and registered (gonogo models).");
  train->add_option_function<std::string>(
           "--soil", [&r](const std::string& v) { r.set_soil_name(v); },
           "a dem-hertz-mindlin soil of the catalogue (gonogo soils)")
      ->type_name("NAME")
      ->required();
  train->add_option("--hidden", o->hidden, "the MLP's tanh layers [default: 64x64]")
      ->type_name("WxW..");
  train->add_flag_function(
      "--unanchored", [&r](int64_t) { r.set_unanchored(true); },
      "no anchoring at rest (d_sigma(0) not forced to 0)");
  train
      ->add_option_function<double>(
          "--pressure-scaled", [&r](double v) { r.set_pressure_reference_pa(v); },
          "the network sees the stress relative to max(p, 0) + this reference pressure and "
          "answers d_sigma relative to it (solvers/ann/README.md) [default: 0, unscaled]")
      ->type_name("PA");
  train->add_flag_function(
      "--hybrid", [&r](int64_t) { r.set_hybrid(true); },
      "each member also has a second network's term homogeneous in the strain increment "
      "(solvers/ann/README.md; off by default: it replays the rig's unloading closer and moves "
      "the curve further from fe-de's)");
  train->add_flag_function(
      "--previous-direction", [&r](int64_t) { r.set_previous_direction(true); },
      "each member also sees the previous step's strain increment direction "
      "(solvers/ann/README.md; off by default)");
  train
      ->add_option_function<double>(
          "--walk-share", [&r](double v) { r.set_walk_share(v); },
          "the random walks' share of the recipe paths' loss, their steps weighed to give it, in "
          "[0, 0.99] [default: 0, their share of the steps]")
      ->type_name("F");
  train->add_option_function<std::vector<std::string>>(
           "--carry",
           [&r](const std::vector<std::string>& names) {
             for (const std::string& name : names) r.add_carried_variables(name);
           },
           "internal variables of the RVE's state the network carries as further inputs and "
           "outputs: coordination_number, solid_fraction [default: none]")
      ->type_name("NAME ...");
  train->add_option_function<std::string>(
           "--from", [&r](const std::string& v) { r.set_from_model(v); },
           "transfer learning: fine-tune this registered model on this soil's data")
      ->type_name("MODEL");
  train->add_option_function<uint32_t>(
           "--members", [&r](uint32_t v) { r.set_members(v); }, "ensemble members [default: 3]")
      ->type_name("N");
  train->add_option_function<uint32_t>(
           "--epochs", [&r](uint32_t v) { r.set_epochs(v); },
           "training epochs [default: 300; 100 when fine-tuning]")
      ->type_name("N");
  train->add_option_function<double>(
           "--learning-rate", [&r](double v) { r.set_learning_rate(v); },
           "Adam's learning rate [default: 3e-3; 1e-3 when fine-tuning]")
      ->type_name("RATE");
  train->add_option_function<uint32_t>(
           "--steps", [&r](uint32_t v) { r.set_steps(v); },
           "strain steps per path after settling [default: 50]")
      ->type_name("N");
  train->add_option_function<uint32_t>(
           "--walks", [&r](uint32_t v) { r.set_walks(v); },
           "random strain walks in the training set [default: 16]")
      ->type_name("N");
  train->add_option("--pressures-kpa", o->pressures_kpa,
                    "confining pressures of the training paths, kPa, increasing "
                    "[default: 2.5 5 10 20 40 80]")
      ->type_name("KPA ...");
  train->add_option_function<uint64_t>(
           "--seed", [&r](uint64_t v) { r.set_seed(v); }, "first member's seed [default: 1]")
      ->type_name("N");
  train->add_option_function<double>(
           "--rig-load-n", [&r](double v) { r.set_rig_load_n(v); },
           "also train on the paths the points of an fe-de rig run take at this wheel load, N "
           "(seed 000's step 2)")
      ->type_name("N");
  train->add_option_function<double>(
           "--rig-diameter-m", [&r](double v) { r.set_rig_diameter_m(v); },
           "the rig wheel's diameter, m [default: 0.5]")
      ->type_name("M");
  train->add_option_function<double>(
           "--rig-width-m", [&r](double v) { r.set_rig_width_m(v); },
           "the rig wheel's width, m [default: 0.2]")
      ->type_name("M");
  train->add_option_function<uint32_t>(
           "--rig-points", [&r](uint32_t v) { r.set_rig_points(v); },
           "recorded paths added to the training set, evenly spread over the bin; half as many "
           "more are held out [default: 8]")
      ->type_name("N");
  train->add_option_function<double>(
           "--fallback-paths-share", [&r](double v) { r.set_fallback_paths_share(v); },
           "also train on the fallback paths kept from fe-ann curves (where their points left a "
           "model's envelope, the paths their RVEs took), their steps carrying this share of the "
           "loss, in [0, 0.99] [default: 0, left out]")
      ->type_name("F");
  train
      ->add_option_function<uint32_t>(
          "--floor-packings", [&r](uint32_t v) { r.set_floor_packings(v); },
          "also run each held-out path (a rig path replayed from its initial stress) on this "
          "many other packings of the soil's RVE; the model's record gives their differences "
          "from its own packing, whose median is the floor under its held-out error, at most 16 "
          "[default: 0, none]")
      ->type_name("N");
  train->add_option_function<std::string>(
           "--name", [&r](const std::string& v) { r.set_name(v); }, "shown in job lists")
      ->type_name("TEXT");
  train->add_flag("--no-wait", o->no_wait, "print the job id and return at once");
  return {train, [o](Client& client) { return RunTrain(client, *o); }};
}

Command AddDatasetCommand(CLI::App& parent) {
  auto soil = std::make_shared<std::string>();
  auto o = std::make_shared<ExportOptions>();
  CLI::App* dataset = parent.add_subcommand(
      "dataset", "the RVE strain-path histories the fe-ann models are trained on");
  dataset->add_option("--soil", *soil, "only this soil's datasets")->type_name("NAME");
  CLI::App* exported = dataset->add_subcommand(
      "export", "write a dataset as a table (CSV or NumPy .npy) with an index of its paths");
  exported->add_option_function<std::string>(
              "DATASET", [o](const std::string& v) { o->request.set_dataset_id(v); },
              "a dataset id (gonogo dataset lists them)")
      ->required();
  exported->add_option("--out", o->out_dir, "directory to write into")->required()->type_name("DIR");
  exported
      ->add_option_function<std::string>(
          "--format", [o](const std::string& v) { o->request.set_format(v); },
          "csv or npy [default: csv]")
      ->check(CLI::IsMember({"csv", "npy"}))
      ->type_name("csv|npy");
  exported
      ->add_option_function<std::string>(
          "--role", [o](const std::string& v) { o->request.set_role(v); },
          "only the histories made for training or held-out sets")
      ->check(CLI::IsMember({"training", "held-out"}))
      ->type_name("training|held-out");
  return {dataset, [soil, o, exported](Client& client) {
            return exported->parsed() ? RunExport(client, *o) : RunDatasets(client, *soil);
          }};
}

void AddSurrogateOptions(CLI::App& app, SurrogateOptions* o, const std::string& model_help) {
  const std::string group = "Surrogate (fe-ann)";
  app.add_option("--model", o->model, model_help)->type_name("ID")->group(group);
  app.add_option("--distance-threshold", o->distance_threshold,
                 "flag a point whose input is farther than D (Mahalanobis) from the training "
                 "inputs; 0: the model's own; default: the server's")
      ->type_name("D")
      ->group(group);
  app.add_option("--spread-threshold", o->spread_threshold,
                 "flag a point whose members' stresses spread more than S of their mean; 0: the "
                 "model's own; default: the server's")
      ->type_name("S")
      ->group(group);
  app.add_option("--pressure-floor-kpa", o->pressure_floor_kpa,
                 "flag a point whose mean compression is below P kPa (the network not trusted "
                 "there); 0: no floor; default: the server's")
      ->type_name("P")
      ->group(group);
  app.add_option("--fallback", o->fallback,
                 "on: a flagged point is answered by the soil's RVE; off: by the network, and "
                 "counted; default: the server's")
      ->check(CLI::Validator(CLI::IsMember({"on", "off"})).description(""))
      ->type_name("on|off")
      ->group(group);
  app.add_option("--return-after-steps", o->return_after_steps,
                 "a fallen-back point returns to the network after N increments in a row it "
                 "would not have been flagged; 0: never; default: the server's")
      ->type_name("N")
      ->group(group);
}

v1::SurrogateGuard GuardFromOptions(const SurrogateOptions& o) {
  v1::SurrogateGuard guard;
  if (o.distance_threshold) guard.set_distance_threshold(*o.distance_threshold);
  if (o.spread_threshold) guard.set_spread_threshold(*o.spread_threshold);
  if (o.pressure_floor_kpa) guard.set_pressure_floor_pa(1e3 * *o.pressure_floor_kpa);
  if (!o.fallback.empty()) guard.set_fallback_enabled(o.fallback == "on");
  if (o.return_after_steps) guard.set_return_after_steps(*o.return_after_steps);
  return guard;
}

}  // namespace gonogo::cli
