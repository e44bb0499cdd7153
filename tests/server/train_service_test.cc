// Training the fe-ann tier's surrogates as jobs on the pool, through the whole service:
// `mpirun -np 3 gonogo-server --fe-de-preset tiny` (rank 0 serving, ranks 1 and 2 computing),
// driven by `gonogo train | models | dataset` and the API.
//   - A training job runs its RVE strain paths on both worker ranks, stores them as a dataset and
//     trains its members on the pool; the model it registers is the one `gonogo-ann --register`
//     makes in-process from the same recipe (same data hash, same held-out errors to the digit),
//     and an fe-ann curve runs with it.
//   - A second training on the same soil takes every path from the dataset (none recomputed); a
//     third adds the paths of an fe-de rig run's points (seed 000's step 2), run on a worker.
//   - The dataset lists and exports (CSV and .npy, with an index naming the rank of each path).
//   - Bad requests are refused by field; a cancelled training stops and registers nothing; a
//     training interrupted by a drain resumes at the next start from the paths it had stored.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "server_process.h"

namespace gonogo::testing {
namespace {

const char* const kRecipe = kSmallSurrogateRecipe;

// `gonogo curve --tier fe-ann` on the tiny rig (the 0.5 x 0.2 m wheel at 1,000 N, slips 0, 0.5
// and 1) with the registered `model`.
CliRun FeAnnCurve(const std::string& endpoint, const std::string& model) {
  return Gonogo(
      endpoint,
      "curve --tier fe-ann --soil seed000_sand_rve100 --wheel-diameter 0.5 "
      "--wheel-width 0.2 --section-height 0.1 --wheel-load 1000 --slip-step 0.5 --model " +
          model);
}

// The text after `label` on the line of `out` that holds `label`, after `from`.
std::string LineAfter(const std::string& out, const std::string& label, size_t from = 0) {
  const size_t at = out.find(label, from);
  if (at == std::string::npos) return "";
  const size_t end = out.find('\n', at);
  return out.substr(at + label.size(), end == std::string::npos ? std::string::npos : end - at - label.size());
}

std::size_t CountOccurrences(const std::string& text, const std::string& what) {
  std::size_t count = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
    ++count;
  }
  return count;
}

// A model's block in `gonogo models` output (its id on a line of its own).
std::string ModelBlock(const std::string& listing, const std::string& id) {
  size_t at = listing.find(id + "\n");
  while (at != std::string::npos && at > 0 && listing[at - 1] != '\n') {
    at = listing.find(id + "\n", at + 1);  // named inside another's block ("fine-tuned from")
  }
  if (at == std::string::npos) return "";
  const size_t end = listing.find("made by:", at);
  return listing.substr(at + id.size(), end - at - id.size());
}

std::string RegisteredId(const std::string& out) {
  std::smatch match;
  if (!std::regex_search(out, match, std::regex("registered (seed000_sand_rve100-[^ \n]+)"))) {
    return "";
  }
  return match[1];
}

// The fields of each line of a CSV table (RFC 4180: a quoted field may hold commas and doubled
// quotes; no field here holds a line break).
std::vector<std::vector<std::string>> CsvRows(const std::string& table) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream lines(table);
  for (std::string line; std::getline(lines, line);) {
    std::vector<std::string> fields(1);
    bool quoted = false;
    for (std::size_t k = 0; k < line.size(); ++k) {
      const char c = line[k];
      if (quoted && c == '"' && k + 1 < line.size() && line[k + 1] == '"') {
        fields.back() += '"';
        ++k;
      } else if (c == '"') {
        quoted = !quoted;
      } else if (c == ',' && !quoted) {
        fields.emplace_back();
      } else {
        fields.back() += c;
      }
    }
    rows.push_back(fields);
  }
  return rows;
}

size_t CountLines(const std::string& text) {
  return static_cast<size_t>(std::count(text.begin(), text.end(), '\n'));
}

v1::Job GetJob(v1::MobilityService::Stub& stub, const std::string& id) {
  grpc::ClientContext ctx;
  v1::GetJobRequest request;
  request.set_job_id(id);
  v1::Job job;
  EXPECT_TRUE(stub.GetJob(&ctx, request, &job).ok());
  return job;
}

// Polls the job until it has done at least `tasks` tasks (or 60 s pass).
v1::Job WaitForTasks(v1::MobilityService::Stub& stub, const std::string& id, uint32_t tasks) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  v1::Job job = GetJob(stub, id);
  while (job.status().tasks_done() < tasks && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    job = GetJob(stub, id);
  }
  return job;
}

std::string SubmittedJobId(const CliRun& run) {
  std::smatch match;
  if (!std::regex_search(run.out, match, std::regex("training job (job-[0-9a-f]+) submitted"))) {
    return "";
  }
  return match[1];
}

TEST(TrainService, TrainsOnThePoolReusesItsDatasetAndMatchesTheOfflineTrainer) {
  ScratchDir dir("train-service");
  const fs::path data = dir.path() / "data";
  fs::create_directories(data);
  ServerProcess server(data, {"--fe-de-preset", "tiny"}, 3);

  const CliRun no_data = Gonogo(server.endpoint(), "dataset");
  ASSERT_EQ(no_data.exit_code, 0) << no_data.out;
  EXPECT_NE(no_data.out.find("no datasets"), std::string::npos) << no_data.out;

  // The walks weighed to carry 60 % of the loss, as the one model's recipe does.
  const CliRun first = Gonogo(server.endpoint(),
                              std::string("train ") + kRecipe + " --hidden 16x16 --walk-share 0.6");
  ASSERT_EQ(first.exit_code, 0) << first.out;
  const std::string trained = RegisteredId(first.out);
  ASSERT_FALSE(trained.empty()) << first.out;
  EXPECT_NE(first.out.find("RVE strain paths: 0 of 27 (0 from dataset"), std::string::npos)
      << first.out;
  EXPECT_NE(first.out.find("mlp-16x16-tanh-anchored, 3 members"), std::string::npos) << first.out;

  // The same data again, another network (unanchored, pressure-scaled): every path from the
  // dataset.
  const CliRun second =
      Gonogo(server.endpoint(), std::string("train ") + kRecipe +
                                    " --hidden 16x16 --unanchored --pressure-scaled 500");
  ASSERT_EQ(second.exit_code, 0) << second.out;
  EXPECT_NE(second.out.find("tasks 30/30  cache hits 27"), std::string::npos)
      << "27 paths from the dataset, 3 members trained:\n" << second.out;
  EXPECT_NE(second.out.find("mlp-16x16-tanh-pressure-scaled-500pa, 3 members"), std::string::npos)
      << second.out;

  // The hybrid (a second network's term homogeneous in the increment) on the same data.
  const CliRun hybrid =
      Gonogo(server.endpoint(),
             std::string("train ") + kRecipe + " --hidden 16x16 --hybrid --pressure-scaled 500");
  ASSERT_EQ(hybrid.exit_code, 0) << hybrid.out;
  EXPECT_NE(hybrid.out.find("tasks 30/30  cache hits 27"), std::string::npos) << hybrid.out;
  EXPECT_NE(hybrid.out.find("mlp-16x16-tanh-anchored-hybrid-pressure-scaled-500pa, 3 members"),
            std::string::npos)
      << hybrid.out;
  const std::string hybrid_model = RegisteredId(hybrid.out);
  const CliRun hybrid_fine_tuned =
      Gonogo(server.endpoint(), "train --soil seed000_sand_rve100 --from " + hybrid_model);
  EXPECT_EQ(hybrid_fine_tuned.exit_code, 3) << hybrid_fine_tuned.out;
  EXPECT_NE(hybrid_fine_tuned.out.find("from_model: model '" + hybrid_model +
                                       "' has the homogeneous term (hybrid), which is not "
                                       "fine-tuned"),
            std::string::npos)
      << hybrid_fine_tuned.out;
  // Networks that also see the previous step's direction, on the same data.
  const CliRun directed =
      Gonogo(server.endpoint(), std::string("train ") + kRecipe +
                                    " --hidden 16x16 --previous-direction --pressure-scaled 500");
  ASSERT_EQ(directed.exit_code, 0) << directed.out;
  EXPECT_NE(directed.out.find("tasks 30/30  cache hits 27"), std::string::npos) << directed.out;
  EXPECT_NE(directed.out.find(
                "mlp-16x16-tanh-anchored-pressure-scaled-500pa-previous-direction, 3 members"),
            std::string::npos)
      << directed.out;
  const std::string directed_model = RegisteredId(directed.out);
  EXPECT_NE(directed_model.find("-ps500pa-pd-"), std::string::npos) << directed_model;

  // The offline trainer on the same recipe, registering into the same data directory.
  const CliRun offline_run = RegisterWithGonogoAnn(data, " --walk-share 0.6");
  ASSERT_EQ(offline_run.exit_code, 0) << offline_run.out;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(offline_run.out, match,
                                std::regex("registered model (seed000_sand_rve100-[^ ]+)")))
      << offline_run.out;
  const std::string offline = match[1];
  const CliRun models = Gonogo(server.endpoint(), "models --soil seed000_sand_rve100");
  ASSERT_EQ(models.exit_code, 0) << models.out;
  const std::string pool_block = ModelBlock(models.out, trained);
  const std::string offline_block = ModelBlock(models.out, offline);
  ASSERT_FALSE(pool_block.empty()) << models.out;
  ASSERT_FALSE(offline_block.empty()) << models.out;
  const std::string pool_hash = LineAfter(pool_block, "hash ");
  EXPECT_EQ(pool_hash.substr(0, 16), LineAfter(offline_block, "hash ").substr(0, 16))
      << "the same training data, path for path:\n" << models.out;
  EXPECT_EQ(LineAfter(pool_block, "held out:"), LineAfter(offline_block, "held out:"))
      << "the same members, trained on other ranks:\n" << models.out;
  EXPECT_EQ(LineAfter(pool_block, "envelope:"), LineAfter(offline_block, "envelope:"))
      << models.out;
  // How the members were trained, recorded by both (the recipe's 60 epochs, its 4 walks weighed,
  // the rest defaults): the same held-out errors above say the weights were the same too.
  EXPECT_EQ(LineAfter(pool_block, "training:"),
            "  epochs=60 batch_size=64 learning_rate=0.003 seed=1 path_stress_weighting=0 "
            "rollout_steps=0 weighted_histories=4")
      << models.out;
  for (const std::string& block : {pool_block, offline_block}) {
    EXPECT_NE(
        LineAfter(block, "data:").find(" steps (the walks 60.0 % of the recipe's loss), hash "),
        std::string::npos)
        << models.out;
  }
  EXPECT_EQ(LineAfter(pool_block, "training:"), LineAfter(offline_block, "training:"))
      << models.out;

  // The dataset: listed, exported as CSV and .npy, each path's rank in the index.
  const CliRun listed = Gonogo(server.endpoint(), "dataset --soil seed000_sand_rve100");
  ASSERT_EQ(listed.exit_code, 0) << listed.out;
  ASSERT_TRUE(std::regex_search(listed.out, match, std::regex("(seed000_sand_rve100-tiny-[0-9a-f]{8})")))
      << listed.out;
  const std::string dataset = match[1];
  ASSERT_TRUE(std::regex_search(
      listed.out, match, std::regex("histories: 27 \\(20 training, 7 held out\\), ([0-9]+) steps")))
      << listed.out;
  const size_t steps = std::stoul(match[1]);
  EXPECT_NE(listed.out.find("(fe-de-1-tiny)"), std::string::npos) << listed.out;
  const fs::path exported = dir.path() / "export";
  const CliRun csv = Gonogo(server.endpoint(),
                            "dataset export " + dataset + " --out " + exported.string());
  ASSERT_EQ(csv.exit_code, 0) << csv.out;
  const std::string table = ReadFile(exported / (dataset + ".csv"));
  EXPECT_EQ(CountLines(table), steps + 1) << "a header and one row per step";
  EXPECT_EQ(table.rfind("history,step,dH_xx,", 0), 0u) << table.substr(0, 200);
  const std::string index = ReadFile(exported / (dataset + ".paths.csv"));
  EXPECT_EQ(CountLines(index), 28u) << index;
  EXPECT_NE(index.find(",rank 1,"), std::string::npos) << "paths ran on both workers:\n" << index;
  EXPECT_NE(index.find(",rank 2,"), std::string::npos) << "paths ran on both workers:\n" << index;
  const CliRun npy = Gonogo(server.endpoint(), "dataset export " + dataset + " --format npy --role "
                                               "held-out --out " + exported.string());
  ASSERT_EQ(npy.exit_code, 0) << npy.out;
  const std::string held_out_index = ReadFile(exported / (dataset + "-held-out.paths.csv"));
  EXPECT_EQ(CountLines(held_out_index), 8u);
  size_t held_out_steps = 0;  // the index's `steps` column, summed
  std::istringstream index_lines(held_out_index);
  std::string line;
  std::getline(index_lines, line);  // header
  while (std::getline(index_lines, line)) {
    std::istringstream fields(line);
    std::string field;
    for (int column = 0; column <= 5; ++column) std::getline(fields, field, ',');
    held_out_steps += std::stoul(field);
  }
  // Debian's NumPy (python3-numpy, with python3-gdal) reads the .npy: one row per step.
  const CliRun numpy = RunShell("/usr/bin/python3 -c \"import numpy, sys; a = numpy.load(sys.argv[1]); "
                                "print(a.shape, a.dtype)\" " +
                                (exported / (dataset + "-held-out.npy")).string());
  ASSERT_EQ(numpy.exit_code, 0) << numpy.out;
  EXPECT_EQ(numpy.out, "(" + std::to_string(held_out_steps) + ", 17) float64\n");
  EXPECT_EQ(CountLines(ReadFile(exported / (dataset + "-held-out.npy.columns.txt"))), 17u);

  // The pool's model computes an fe-ann curve.
  const CliRun curve = FeAnnCurve(server.endpoint(), trained);
  ASSERT_EQ(curve.exit_code, 0) << curve.out;
  EXPECT_NE(curve.out.find("surrogate model " + trained), std::string::npos) << curve.out;
  // So does the hybrid, its second network loaded from the registry beside the first.
  const CliRun hybrid_curve = FeAnnCurve(server.endpoint(), hybrid_model);
  ASSERT_EQ(hybrid_curve.exit_code, 0) << hybrid_curve.out;
  EXPECT_NE(hybrid_curve.out.find("surrogate model " + hybrid_model), std::string::npos)
      << hybrid_curve.out;
  // And the one that sees the previous direction, each point's last increment given to it.
  const CliRun directed_curve = FeAnnCurve(server.endpoint(), directed_model);
  ASSERT_EQ(directed_curve.exit_code, 0) << directed_curve.out;
  EXPECT_NE(directed_curve.out.find("surrogate model " + directed_model), std::string::npos)
      << directed_curve.out;

  // Seed 000's step 2: the paths of a rig run's points join the data, the run on one worker.
  const CliRun with_rig = Gonogo(server.endpoint(), std::string("train ") + kRecipe +
                                                        " --hidden 16x16 --rig-load-n 1000 "
                                                        "--rig-points 4");
  ASSERT_EQ(with_rig.exit_code, 0) << with_rig.out;
  EXPECT_NE(with_rig.out.find("RVE strain paths and rig paths: 27 of 33 (27 from dataset"),
            std::string::npos)
      << with_rig.out;
  EXPECT_NE(with_rig.out.find("tasks 36/36  cache hits 27"), std::string::npos) << with_rig.out;
  EXPECT_NE(with_rig.out.find("; rig point 2 "), std::string::npos) << "held out:\n" << with_rig.out;
  EXPECT_EQ(with_rig.out.find("; rig point 3 "), std::string::npos) << "half as many held out:\n"
                                                                   << with_rig.out;
  const CliRun with_rig_listed = Gonogo(server.endpoint(), "dataset");
  const CliRun rig_export = Gonogo(server.endpoint(), "dataset export " + dataset + " --out " +
                                                          (dir.path() / "export2").string());
  ASSERT_EQ(rig_export.exit_code, 0) << rig_export.out;
  const std::string rig_index = ReadFile(dir.path() / "export2" / (dataset + ".paths.csv"));
  // The fe-ann curve above kept its fallback paths here too (training histories of their own).
  const std::size_t curve_fallbacks = CountOccurrences(rig_index, ",fallback,\"fallback ");
  EXPECT_NE(with_rig_listed.out.find("histories: " + std::to_string(33 + curve_fallbacks) + " (" +
                                     std::to_string(24 + curve_fallbacks) +
                                     " training, 9 held out)"),
            std::string::npos)
      << curve_fallbacks << " fallback paths:\n" << with_rig_listed.out;
  EXPECT_NE(rig_index.find(",rig-point,rig 1000 N point 4,training,"), std::string::npos)
      << rig_index;
  EXPECT_NE(rig_index.find(",rig-point,rig point 2,held-out,"), std::string::npos) << rig_index;

  // The floor under the held-out errors: each held-out laboratory path also run on two other
  // packings of the RVE (14 new paths, the recipe's 27 from the dataset), its differences from
  // its own packing in the model's record, the worst path's in the job's last word.
  const CliRun floor = Gonogo(
      server.endpoint(), std::string("train ") + kRecipe + " --hidden 16x16 --floor-packings 2");
  ASSERT_EQ(floor.exit_code, 0) << floor.out;
  EXPECT_NE(floor.out.find("RVE strain paths: 27 of 41 (14 on other packings; 27 from dataset"),
            std::string::npos)
      << floor.out;
  const std::string floor_id = RegisteredId(floor.out);
  ASSERT_FALSE(floor_id.empty()) << floor.out;
  const std::string floor_held_out = LineAfter(floor.out, "held out:");
  EXPECT_EQ(CountOccurrences(floor_held_out, "(other packings "), 7u)
      << "each of the 7 held-out laboratory paths:\n"
      << floor.out;
  // The packings answer a 100-grain RVE's triaxial far apart (solvers/ann/README.md: 20-70 %).
  ASSERT_TRUE(std::regex_search(
      floor_held_out, match,
      std::regex("triaxial [0-9.]+ kPa [0-9.]+ % \\(other packings ([0-9.]+) % to ([0-9.]+) %, "
                 "median ([0-9.]+) %\\)")))
      << floor_held_out;
  EXPECT_GT(std::stod(match[1]), 1.0) << floor_held_out;
  // Of two packings, the median is their mean (to the printed digit).
  EXPECT_NEAR(std::stod(match[3]), 0.5 * (std::stod(match[1]) + std::stod(match[2])), 0.051)
      << floor_held_out;
  EXPECT_NE(floor.out.find("other packings of the RVE "), std::string::npos)
      << "the job's last word names the worst path's floor:\n"
      << floor.out;
  // The same model's record without the floor: the paths on other packings are data, not
  // training (same data hash as the first 16x16 model's).
  const CliRun floor_models = Gonogo(server.endpoint(), "models --soil seed000_sand_rve100");
  EXPECT_EQ(LineAfter(ModelBlock(floor_models.out, floor_id), "hash ").substr(0, 16),
            LineAfter(ModelBlock(floor_models.out, trained), "hash ").substr(0, 16))
      << floor_models.out;
  // One packing of the two: every path from the dataset, each packing kept under its own key.
  const CliRun floor_again = Gonogo(
      server.endpoint(), std::string("train ") + kRecipe + " --hidden 16x16 --floor-packings 1");
  ASSERT_EQ(floor_again.exit_code, 0) << floor_again.out;
  EXPECT_NE(floor_again.out.find("tasks 37/37  cache hits 34"), std::string::npos)
      << floor_again.out;
  EXPECT_EQ(CountOccurrences(LineAfter(floor_again.out, "held out:"), "(another packing "), 7u)
      << floor_again.out;
  const std::string floor_export_dir = (dir.path() / "export-floor").string();
  ASSERT_EQ(Gonogo(server.endpoint(),
                   "dataset export " + dataset + " --role held-out --out " + floor_export_dir)
                .exit_code,
            0);
  const std::string floor_index =
      ReadFile(fs::path(floor_export_dir) / (dataset + "-held-out.paths.csv"));
  EXPECT_EQ(CountOccurrences(floor_index, " on packing 2,held-out,"), 7u) << floor_index;
  EXPECT_EQ(CountOccurrences(floor_index, " on packing 3,held-out,"), 7u) << floor_index;

  // A held-out rig path's floor: the path replayed from its initial stress on the other packing
  // (the two held-out rig paths' replays new; the 40 other paths from the dataset). The job's last
  // word and the record give how far the model lies beyond the floors, what the registry ranks by.
  const CliRun rig_floor =
      Gonogo(server.endpoint(), std::string("train ") + kRecipe +
                                    " --hidden 16x16 --rig-load-n 1000 --rig-points 4 "
                                    "--floor-packings 1");
  ASSERT_EQ(rig_floor.exit_code, 0) << rig_floor.out;
  EXPECT_NE(rig_floor.out.find("tasks 45/45  cache hits 40"), std::string::npos) << rig_floor.out;
  const std::string rig_floor_held_out = LineAfter(rig_floor.out, "held out:");
  EXPECT_EQ(CountOccurrences(rig_floor_held_out, "(another packing "), 9u) << rig_floor.out;
  ASSERT_TRUE(
      std::regex_search(rig_floor_held_out, match,
                        std::regex("; rig point 1 [0-9.]+ % \\(another packing ([0-9.]+) %")))
      << rig_floor_held_out;
  EXPECT_GT(std::stod(match[1]), 0.0) << "another packing answers the rig path differently";
  EXPECT_NE(rig_floor.out.find("beyond the floors: "), std::string::npos) << rig_floor.out;
  EXPECT_NE(rig_floor.out.find(", beyond the floors "), std::string::npos)
      << "the job's last word:\n"
      << rig_floor.out;

  // Refused by field, before anything runs.
  const std::vector<std::pair<std::string, std::string>> refusals = {
      {"train --soil no-such-soil", "soil_name: no dem-hertz-mindlin soil 'no-such-soil'"},
      {"train --soil lll_dry_sand", "soil_name: no dem-hertz-mindlin soil 'lll_dry_sand'"},
      {"train --soil seed000_sand_rve100 --from no-such", "from_model: no model 'no-such'"},
      {"train --soil seed000_sand_rve100 --from " + trained + " --hidden 8x8",
       "hidden_widths: a fine-tuned model keeps its base model's layers"},
      {"train --soil seed000_sand_rve100 --pressures-kpa 5 2", "pressures_kpa: must be in"},
      {"train --soil seed000_sand_rve100 --members 2", "members: must lie in [3, 64]"},
      {"train --soil seed000_sand_rve100 --rig-points 4", "rig_load_n: is needed with"},
      {"train --soil seed000_sand_rve100 --floor-packings 17",
       "floor_packings: must be at most 16"},
      {"train --soil seed000_sand_rve100 --rig-load-n 1000 --rig-width-m 0.6",
       "rig_width_m: must lie in (0, rig_diameter_m]"},
      {"dataset export no-such --out " + exported.string(), "NOT_FOUND: dataset_id"},
      {"train --soil seed000_sand_rve100 --carry void_ratio",
       "carried_variables: 'void_ratio' is not a variable of the RVE's state"},
      {"train --soil seed000_sand_rve100 --carry fabric_xz",
       "carried_variables: 'fabric_xz' is a tensor's component"},
      {"train --soil seed000_sand_rve100 --from " + trained + " --carry coordination_number",
       "carried_variables: a fine-tuned model carries what its base model carries"},
      {"train --soil seed000_sand_rve100 --pressure-scaled 0.5",
       "pressure_reference_pa: must be 0 (no scaling) or in [1, 1e7] Pa"},
      {"train --soil seed000_sand_rve100 --from " + trained + " --pressure-scaled 500",
       "pressure_reference_pa: a fine-tuned model keeps its base model's pressure scaling"},
      {"train --soil seed000_sand_rve100 --walk-share 1", "walk_share: must lie in [0, 0.99]"},
      {"train --soil seed000_sand_rve100 --hybrid --unanchored",
       "hybrid: needs the anchored network (not unanchored)"},
      {"train --soil seed000_sand_rve100 --from " + trained + " --hybrid",
       "hybrid: a fine-tuned model keeps its base model's form"},
      {"train --soil seed000_sand_rve100 --from " + trained + " --previous-direction",
       "previous_direction: a fine-tuned model keeps its base model's form"},
  };
  for (const auto& [args, message] : refusals) {
    const CliRun refused = Gonogo(server.endpoint(), args);
    EXPECT_EQ(refused.exit_code, 3) << args << ": " << refused.out;
    EXPECT_NE(refused.out.find(message), std::string::npos) << args << ": " << refused.out;
  }
  const CliRun bad_format = Gonogo(server.endpoint(), "dataset export " + dataset +
                                                          " --format xls --out " + exported.string());
  EXPECT_EQ(bad_format.exit_code, 2) << bad_format.out;

  // A network that carries the RVE's coordination number: its paths record it, in a dataset of
  // their own (none of the stored paths, which do not, is reused), the registered architecture
  // says what it carries, the export has the column, and an fe-ann curve runs with it.
  const CliRun carrying = Gonogo(server.endpoint(), std::string("train ") + kRecipe +
                                                        " --hidden 16x16 --carry coordination_number");
  ASSERT_EQ(carrying.exit_code, 0) << carrying.out;
  const std::string carrying_id = RegisteredId(carrying.out);
  ASSERT_FALSE(carrying_id.empty()) << carrying.out;
  EXPECT_NE(carrying.out.find("RVE strain paths: 0 of 27 (0 from dataset " + dataset +
                              "+coordination_number"),
            std::string::npos)
      << carrying.out;
  EXPECT_NE(carrying.out.find("mlp-16x16-tanh-anchored-carrying-coordination_number, 3 members"),
            std::string::npos)
      << carrying.out;
  const CliRun carried_export =
      Gonogo(server.endpoint(), "dataset export " + dataset + "+coordination_number --out " +
                                    (dir.path() / "export3").string());
  ASSERT_EQ(carried_export.exit_code, 0) << carried_export.out;
  const std::string carried_table =
      ReadFile(dir.path() / "export3" / (dataset + "+coordination_number.csv"));
  EXPECT_NE(carried_table.find(",sigma_xy_pa,coordination_number\n"), std::string::npos)
      << carried_table.substr(0, 300);
  const CliRun carrying_curve = FeAnnCurve(server.endpoint(), carrying_id);
  ASSERT_EQ(carrying_curve.exit_code, 0) << carrying_curve.out;
  EXPECT_NE(carrying_curve.out.find("surrogate model " + carrying_id), std::string::npos)
      << carrying_curve.out;

  // Where the curve's points left that model's envelope, their RVEs' paths were kept in its
  // dataset (kind "fallback", recording the coordination number as the model does), and a
  // fine-tuning trains on them beside the recipe's paths.
  const CliRun kept_export =
      Gonogo(server.endpoint(), "dataset export " + dataset + "+coordination_number --out " +
                                    (dir.path() / "export4").string());
  ASSERT_EQ(kept_export.exit_code, 0) << kept_export.out;
  const std::string kept_index =
      ReadFile(dir.path() / "export4" / (dataset + "+coordination_number.paths.csv"));
  const std::size_t fallback_paths = CountOccurrences(kept_index, ",fallback,\"fallback ");
  std::cout << "  the carrying model's curve kept " << fallback_paths << " fallback paths\n";
  ASSERT_GT(fallback_paths, 0u) << kept_index;
  // A fallback path's name holds commas: quoted, so that every row reads as the header's 13 fields.
  std::size_t fallback_rows = 0;
  for (const std::vector<std::string>& row : CsvRows(kept_index)) {
    ASSERT_EQ(row.size(), 13u) << kept_index;
    if (row[1] != "fallback") continue;
    ++fallback_rows;
    EXPECT_NE(row[2].find(", model " + carrying_id + ", 0.5 x 0.2 m wheel at 1000 N"),
              std::string::npos)
        << row[2];
    EXPECT_EQ(row[3], "training");
  }
  EXPECT_EQ(fallback_rows, fallback_paths);
  // The recipe's walks weighed too: they carry half the recipe paths' loss, the fallback paths
  // 20 % of the whole.
  const CliRun refined =
      Gonogo(server.endpoint(), std::string("train ") + kRecipe + " --from " + carrying_id +
                                    " --fallback-paths-share 0.2 --walk-share 0.5");
  ASSERT_EQ(refined.exit_code, 0) << refined.out;
  EXPECT_NE(refined.out.find(std::to_string(fallback_paths) + " of them fallback paths"),
            std::string::npos)
      << refined.out;
  const std::string refined_id = RegisteredId(refined.out);
  ASSERT_FALSE(refined_id.empty()) << refined.out;
  const CliRun refined_models = Gonogo(server.endpoint(), "models --soil seed000_sand_rve100");
  EXPECT_NE(LineAfter(ModelBlock(refined_models.out, refined_id), "hash "),
            LineAfter(ModelBlock(refined_models.out, carrying_id), "hash "))
      << "the fallback paths are in its training data:\n" << refined_models.out;
  EXPECT_NE(ModelBlock(refined_models.out, refined_id)
                .find("(the walks 50.0 % of the recipe's loss; " + std::to_string(fallback_paths) +
                      " fallback paths, 20.0 % of the loss)"),
            std::string::npos)
      << "the model's record names its fallback paths:\n"
      << refined_models.out;
  EXPECT_NE(LineAfter(ModelBlock(refined_models.out, refined_id), "training:")
                .find(" weighted_histories=" + std::to_string(4 + fallback_paths)),
            std::string::npos)
      << "the 4 walks and every fallback path weighed:\n"
      << refined_models.out;
  std::cout << "  the fine-tuned model's data:"
            << LineAfter(ModelBlock(refined_models.out, refined_id), "data:") << "\n";
  EXPECT_EQ(ModelBlock(refined_models.out, carrying_id).find("fallback paths"), std::string::npos)
      << refined_models.out;
  for (const auto& [args, code_and_message] :
       std::vector<std::pair<std::string, std::string>>{
           {" --fallback-paths-share 1.5", "INVALID_ARGUMENT: fallback_paths_share: must be in"},
           {" --carry solid_fraction --fallback-paths-share 0.2",
            "FAILED_PRECONDITION: fallback_paths_share: dataset " + dataset +
                "+solid_fraction holds no fallback paths"}}) {
    const CliRun refused =
        Gonogo(server.endpoint(), std::string("train ") + kRecipe + " --hidden 16x16" + args);
    EXPECT_EQ(refused.exit_code, 3) << args << ": " << refused.out;
    EXPECT_NE(refused.out.find(code_and_message), std::string::npos) << args << ": " << refused.out;
  }
  EXPECT_EQ(server.Terminate(), 0);
}

TEST(TrainService, ACancelledTrainingStopsAndADrainedOneResumesFromItsStoredPaths) {
  ScratchDir dir("train-service-resume");
  const fs::path data = dir.path() / "data";
  fs::create_directories(data);
  std::string drained;
  uint32_t stored_before_drain = 0;
  {
    // Every task waits 400 ms first, so that the jobs are caught mid-way.
    ServerProcess server(data, {"--fe-de-preset", "tiny", "--task-delay-ms", "400"}, 3);
    auto stub = server.Stub();

    const CliRun cancelled_run = Gonogo(
        server.endpoint(), "train --soil seed000_sand_rve100 --steps 21 --walks 4 --epochs 60 --hidden 8 --no-wait");
    ASSERT_EQ(cancelled_run.exit_code, 0) << cancelled_run.out;
    const std::string cancelled = SubmittedJobId(cancelled_run);
    ASSERT_FALSE(cancelled.empty()) << cancelled_run.out;
    EXPECT_GE(WaitForTasks(*stub, cancelled, 2).status().tasks_done(), 2u);
    const auto cancel_start = std::chrono::steady_clock::now();
    const CliRun cancel = Gonogo(server.endpoint(), "cancel " + cancelled);
    ASSERT_EQ(cancel.exit_code, 0) << cancel.out;
    const v1::JobStatus end = WaitForEnd(*stub, cancelled);
    EXPECT_EQ(end.state(), v1::JOB_STATE_CANCELLED) << end.message();
    EXPECT_LT(std::chrono::steady_clock::now() - cancel_start, std::chrono::seconds(10));
    const CliRun none = Gonogo(server.endpoint(), "models");
    EXPECT_NE(none.out.find("no surrogate models"), std::string::npos) << none.out;

    const CliRun drained_run =
        Gonogo(server.endpoint(), std::string("train ") + kRecipe + " --hidden 8 --no-wait");
    ASSERT_EQ(drained_run.exit_code, 0) << drained_run.out;
    drained = SubmittedJobId(drained_run);
    ASSERT_FALSE(drained.empty()) << drained_run.out;
    EXPECT_GE(WaitForTasks(*stub, drained, 4).status().tasks_done(), 4u);
    EXPECT_EQ(server.Terminate(), 0);
  }
  {
    // What the drain left: the job queued again, its finished paths in the dataset.
    ServerProcess restarted(data, {"--fe-de-preset", "tiny"}, 3);
    auto stub = restarted.Stub();
    const v1::JobStatus resumed = WaitForEnd(*stub, drained);
    EXPECT_EQ(resumed.state(), v1::JOB_STATE_DONE) << resumed.message();
    stored_before_drain = resumed.cache_hits();
    EXPECT_GE(stored_before_drain, 4u) << "paths stored before the drain are not run again";
    EXPECT_LT(stored_before_drain, 27u) << "the drain came mid-way";
    const CliRun models = Gonogo(restarted.endpoint(), "models");
    EXPECT_NE(models.out.find("mlp-8-tanh-anchored, 3 members"), std::string::npos) << models.out;
    EXPECT_EQ(restarted.Terminate(), 0);
  }
}

}  // namespace
}  // namespace gonogo::testing
