// The fe-ann tier through the whole service: `mpirun -np 2 gonogo-server --fe-de-preset tiny`
// (rank 0 serving, rank 1 computing), driven by the `gonogo` command line. Before a model exists a
// curve or a map on fe-ann is refused with FAILED_PRECONDITION naming the command that trains one;
// `gonogo-ann --register` trains one on the soil's RVE into the server's data directory;
// `gonogo models` lists it; the curve is then computed on the worker rank with it (the model's id
// crosses to the rank with the task), then comes from the cache; a map on fe-ann runs; an unknown
// model (for a curve or a map), or a model given to another tier, is refused by field. A server
// started with the guard set otherwise (--fe-ann-no-fallback, --fe-ann-distance-threshold) names
// it in the tier's version, under which a request's own guard (gonogo curve --fallback off
// --distance-threshold 30 on the first server) had already computed the curve on the worker rank;
// a request there may set the guard back (its curve is the first server's); a negative threshold,
// and a return from a fallback that is off, are refused by flag and, in a request, by field (a
// guard on another tier too).
#include <gtest/gtest.h>

#include <cstdlib>
#include <regex>

#include "server_process.h"

namespace gonogo::testing {
namespace {

const char kWheel[] =
    "curve --tier fe-ann --soil seed000_sand_rve100 --wheel-diameter 0.5 --wheel-width 0.2 "
    "--section-height 0.1 --wheel-load 1000 --slip-step 0.25";

TEST(FeAnnService, RefusedWithoutAModelThenComputedWithARegisteredOne) {
  ScratchDir dir("fe-ann-service");
  const fs::path data = dir.path() / "data";
  fs::create_directories(data);
  ServerProcess server(data, {"--fe-de-preset", "tiny"}, 2);

  const CliRun tiers = Gonogo(server.endpoint(), "tiers");
  ASSERT_EQ(tiers.exit_code, 0) << tiers.out;
  EXPECT_NE(tiers.out.find("fe-ann (fe-ann-3-tiny)"), std::string::npos) << tiers.out;
  const CliRun none = Gonogo(server.endpoint(), "models");
  ASSERT_EQ(none.exit_code, 0) << none.out;
  EXPECT_NE(none.out.find("no surrogate models"), std::string::npos) << none.out;

  const CliRun refused = Gonogo(server.endpoint(), kWheel);
  EXPECT_EQ(refused.exit_code, 3) << refused.out;
  EXPECT_NE(refused.out.find("FAILED_PRECONDITION"), std::string::npos) << refused.out;
  EXPECT_NE(refused.out.find("surrogate_model"), std::string::npos) << refused.out;
  EXPECT_NE(refused.out.find("gonogo train --soil NAME"),
            std::string::npos)
      << refused.out;

  // A map's inputs: every soil class on the DE soil, a wheel pair carrying the curve's 1000 N on
  // the same tyre (so that, later, the map's one curve is the cached one). Without a model the map
  // is refused at submission.
  ASSERT_TRUE(MakeSampleTerrain(dir.path() / "terrain", 8));
  const fs::path terrain = dir.path() / "terrain";
  WriteDeSoilTableAndRigWheels(terrain);
  const std::string map_args =
      "map --cone-index " + (terrain / "cone_index.tif").string() + " --elevation " +
      (terrain / "elevation.tif").string() + " --soil-class " +
      (terrain / "soil_class.tif").string() + " --soil-table " +
      (terrain / "de_soils.json").string() + " --vehicle " +
      (terrain / "small_wheels.json").string() + " --tier fe-ann --slip-step 0.25 --out ";
  const CliRun map_refused =
      Gonogo(server.endpoint(), map_args + (dir.path() / "map0").string());
  EXPECT_EQ(map_refused.exit_code, 3) << map_refused.out;
  EXPECT_NE(map_refused.out.find("FAILED_PRECONDITION"), std::string::npos) << map_refused.out;
  EXPECT_FALSE(fs::exists(dir.path() / "map0" / "gonogo.tif"));

  const CliRun trained = RegisterWithGonogoAnn(data);
  ASSERT_EQ(trained.exit_code, 0) << trained.out;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(trained.out, match,
                                std::regex("registered model (seed000_sand_rve100-[^ ]+)")))
      << trained.out;
  const std::string id = match[1];

  const CliRun listed = Gonogo(server.endpoint(), "models --soil seed000_sand_rve100");
  ASSERT_EQ(listed.exit_code, 0) << listed.out;
  EXPECT_NE(listed.out.find(id), std::string::npos) << listed.out;
  EXPECT_NE(listed.out.find("mlp-16x16-tanh-anchored, 3 members"), std::string::npos) << listed.out;
  EXPECT_NE(listed.out.find("RVEs of the tiny fe-de configuration"), std::string::npos)
      << listed.out;

  const CliRun first = Gonogo(server.endpoint(), std::string(kWheel) + " --csv");
  ASSERT_EQ(first.exit_code, 0) << first.out;
  EXPECT_NE(first.out.find(";model=" + id + "\n"), std::string::npos) << "in the cache key: "
                                                                       << first.out;
  const CliRun again = Gonogo(server.endpoint(), std::string(kWheel) + " --model " + id);
  ASSERT_EQ(again.exit_code, 0) << again.out;
  EXPECT_NE(again.out.find("surrogate model " + id + ", from the cache by rank 1"),
            std::string::npos)
      << "computed on the worker rank: " << again.out;

  // The request's own guard: the curve computed anew on the worker rank, its version naming the
  // guard the rank ran (the guard crossed to the rank with the task).
  const std::string kOwnGuard = " --fallback off --distance-threshold 30";
  const CliRun own_guard = Gonogo(server.endpoint(), std::string(kWheel) + kOwnGuard);
  ASSERT_EQ(own_guard.exit_code, 0) << own_guard.out;
  EXPECT_NE(own_guard.out.find("tier fe-ann (fe-ann-3-tiny-nofallback-d30-s0)"), std::string::npos)
      << own_guard.out;
  EXPECT_NE(own_guard.out.find("surrogate model " + id + ", computed by rank 1"), std::string::npos)
      << "not the default guard's cached curve: " << own_guard.out;
  // A pressure floor above every stress of the soil: each of the rig's 128 points is answered by
  // its RVE from its first increment, and the run says the floor flagged them (and which of them
  // the model's own thresholds flagged too).
  const CliRun floored =
      Gonogo(server.endpoint(), std::string(kWheel) + " --pressure-floor-kpa 1000000");
  ASSERT_EQ(floored.exit_code, 0) << floored.out;
  EXPECT_NE(floored.out.find("tier fe-ann (fe-ann-3-tiny-p1e+09)"), std::string::npos)
      << floored.out;
  std::smatch floored_run;
  ASSERT_TRUE(std::regex_search(
      floored.out, floored_run,
      std::regex("(\\d+) of its points fell back to their RVEs, at steps 0, 0, [^;]* of 900"
                 "(?:, \\d+ beyond the envelope's distance)?(?:, \\d+ beyond the members' "
                 "spread)?, (\\d+) below the pressure floor")))
      << floored.out;
  EXPECT_GE(std::stoi(floored_run[1]), 128) << floored.out;
  EXPECT_EQ(floored_run[1], floored_run[2]) << floored.out;

  // The curve's provenance says how its points were answered, computed and from the cache alike:
  // with the fallback off none fell back; with it on (the cached curve above) the line names the
  // fallbacks, when, and which of the guard's tests flagged them, or says there were none.
  const std::regex run_line("surrogate run: [^\n]*");
  std::smatch computed_run, cached_run;
  ASSERT_TRUE(std::regex_search(own_guard.out, computed_run, run_line)) << own_guard.out;
  EXPECT_NE(computed_run.str().find("surrogate run: no point fell back to its RVE in "),
            std::string::npos)
      << computed_run.str();
  const CliRun own_guard_again = Gonogo(server.endpoint(), std::string(kWheel) + kOwnGuard);
  ASSERT_TRUE(std::regex_search(own_guard_again.out, cached_run, run_line)) << own_guard_again.out;
  EXPECT_NE(own_guard_again.out.find("from the cache"), std::string::npos) << own_guard_again.out;
  EXPECT_EQ(cached_run.str(), computed_run.str());
  std::smatch guarded_run;
  ASSERT_TRUE(std::regex_search(again.out, guarded_run, run_line)) << again.out;
  std::cout << "  " << guarded_run.str() << "\n  with the fallback off: " << computed_run.str()
            << "\n";
  EXPECT_TRUE(std::regex_match(
      guarded_run.str(),
      std::regex(
          "surrogate run: (no point fell back to its RVE in [0-9]+ FE steps|[0-9]+ (point|of "
          "its points) fell back to (its RVE|their RVEs), at steps? [0-9, and]+( and [0-9]+ "
          "more)? of [0-9]+(, [0-9]+ beyond the envelope's distance|, [0-9]+ beyond the "
          "members' spread){1,2} \\([0-9]+ paths kept for training\\)); network [0-9.e+-]+ s "
          "for [0-9]+ point updates(, fallbacks [0-9.e+-]+ s)?")))
      << guarded_run.str();

  // A curve job's progress tells how its run goes: its points fallen back so far (the fallbacks
  // are what makes an fe-ann curve long). A guard of its own, so that it is computed.
  const CliRun as_job =
      Gonogo(server.endpoint(), std::string(kWheel) + " --job --return-after-steps 5");
  ASSERT_EQ(as_job.exit_code, 0) << as_job.out;
  std::smatch progress_note;
  EXPECT_TRUE(std::regex_search(
      as_job.out, progress_note,
      std::regex("computing the traction curve: [0-9]+ %; (no point fallen back to its RVE|1 "
                 "point fallen back to its RVE|[0-9]+ points fallen back to their RVEs)[^\n]*")))
      << as_job.out;
  std::cout << "  a job's progress: " << progress_note.str() << "\n";
  for (const auto& [flags, field] :
       {std::pair{" --distance-threshold -1", "surrogate_guard.distance_threshold"},
        std::pair{" --fallback off --return-after-steps 5", "surrogate_guard.return_after_steps"}}) {
    const CliRun bad_guard = Gonogo(server.endpoint(), std::string(kWheel) + flags);
    EXPECT_EQ(bad_guard.exit_code, 3) << bad_guard.out;
    EXPECT_NE(bad_guard.out.find("INVALID_ARGUMENT"), std::string::npos) << bad_guard.out;
    EXPECT_NE(bad_guard.out.find(field), std::string::npos) << bad_guard.out;
  }

  const CliRun unknown = Gonogo(server.endpoint(), std::string(kWheel) + " --model no-such");
  EXPECT_EQ(unknown.exit_code, 3) << unknown.out;
  EXPECT_NE(unknown.out.find("INVALID_ARGUMENT"), std::string::npos) << unknown.out;
  EXPECT_NE(unknown.out.find("surrogate_model: no registered model 'no-such'"), std::string::npos)
      << unknown.out;
  const CliRun other_tier =
      Gonogo(server.endpoint(),
             "curve --tier bekker --soil lll_dry_sand --wheel-diameter 0.5 --wheel-width 0.2 "
             "--section-height 0.1 --wheel-load 1000 --model " + id);
  EXPECT_EQ(other_tier.exit_code, 3) << other_tier.out;
  EXPECT_NE(other_tier.out.find("the bekker tier takes no surrogate model"), std::string::npos)
      << other_tier.out;
  const CliRun other_tier_guard =
      Gonogo(server.endpoint(),
             "curve --tier bekker --soil lll_dry_sand --wheel-diameter 0.5 --wheel-width 0.2 "
             "--section-height 0.1 --wheel-load 1000 --fallback off");
  EXPECT_EQ(other_tier_guard.exit_code, 3) << other_tier_guard.out;
  EXPECT_NE(other_tier_guard.out.find("surrogate_guard: the bekker tier has no surrogate to guard"),
            std::string::npos)
      << other_tier_guard.out;

  const std::string out = (dir.path() / "map").string();
  const CliRun map = Gonogo(server.endpoint(), map_args + out);
  ASSERT_EQ(map.exit_code, 0) << map.out;
  EXPECT_TRUE(fs::exists(fs::path(out) / "gonogo.tif"));
  EXPECT_NE(map.out.find("tasks 1/1  cache hits 1"), std::string::npos) << map.out;
  // A map's guard keys its curves as a curve's does: its one curve is the guarded one above.
  const CliRun guarded_map =
      Gonogo(server.endpoint(), map_args + (dir.path() / "map-guarded").string() + kOwnGuard);
  ASSERT_EQ(guarded_map.exit_code, 0) << guarded_map.out;
  EXPECT_NE(guarded_map.out.find("tasks 1/1  cache hits 1"), std::string::npos) << guarded_map.out;
  const CliRun bad_guard_map = Gonogo(
      server.endpoint(), map_args + (dir.path() / "map3").string() + " --spread-threshold -1");
  EXPECT_EQ(bad_guard_map.exit_code, 3) << bad_guard_map.out;
  EXPECT_NE(bad_guard_map.out.find("surrogate_guard.spread_threshold"), std::string::npos)
      << bad_guard_map.out;
  const CliRun bad_floor_map = Gonogo(
      server.endpoint(), map_args + (dir.path() / "map4").string() + " --pressure-floor-kpa -2");
  EXPECT_EQ(bad_floor_map.exit_code, 3) << bad_floor_map.out;
  EXPECT_NE(bad_floor_map.out.find("surrogate_guard.pressure_floor_pa"), std::string::npos)
      << bad_floor_map.out;
  const CliRun bad_map =
      Gonogo(server.endpoint(), map_args + (dir.path() / "map2").string() + " --model no-such");
  EXPECT_EQ(bad_map.exit_code, 3) << bad_map.out;
  EXPECT_NE(bad_map.out.find("surrogate_model"), std::string::npos) << bad_map.out;
  EXPECT_EQ(server.Terminate(), 0);

  ServerProcess guarded(data,
                        {"--fe-de-preset", "tiny", "--fe-ann-no-fallback",
                         "--fe-ann-distance-threshold", "30", "--fe-ann-pressure-floor-kpa", "4"},
                        2);
  const CliRun guarded_tiers = Gonogo(guarded.endpoint(), "tiers");
  ASSERT_EQ(guarded_tiers.exit_code, 0) << guarded_tiers.out;
  EXPECT_NE(guarded_tiers.out.find("fe-ann (fe-ann-3-tiny-nofallback-d30-s0-p4000)"),
            std::string::npos)
      << guarded_tiers.out;
  // Not the default guard's cached curve: the one the request's own guard computed on the first
  // server, under the same version (the request takes this server's floor away).
  const CliRun unguarded = Gonogo(
      guarded.endpoint(), std::string(kWheel) + " --model " + id + " --pressure-floor-kpa 0");
  ASSERT_EQ(unguarded.exit_code, 0) << unguarded.out;
  EXPECT_NE(unguarded.out.find("tier fe-ann (fe-ann-3-tiny-nofallback-d30-s0)"), std::string::npos)
      << unguarded.out;
  EXPECT_NE(unguarded.out.find("surrogate model " + id + ", from the cache by rank 1"),
            std::string::npos)
      << unguarded.out;
  // A request sets the deployment's guard back to the model's own: the first server's curve.
  const CliRun set_back =
      Gonogo(guarded.endpoint(),
             std::string(kWheel) + " --fallback on --distance-threshold 0 --pressure-floor-kpa 0");
  ASSERT_EQ(set_back.exit_code, 0) << set_back.out;
  EXPECT_NE(set_back.out.find("tier fe-ann (fe-ann-3-tiny),"), std::string::npos) << set_back.out;
  EXPECT_NE(set_back.out.find("from the cache"), std::string::npos) << set_back.out;
  const CliRun no_return =
      Gonogo(guarded.endpoint(), std::string(kWheel) + " --return-after-steps 5");
  EXPECT_EQ(no_return.exit_code, 3) << no_return.out;
  EXPECT_NE(no_return.out.find("surrogate_guard.return_after_steps"), std::string::npos)
      << "this server's fallback is off: " << no_return.out;
  EXPECT_EQ(guarded.Terminate(), 0);
}

TEST(FeAnnService, RefusesAGuardItCannotKeep) {
  ScratchDir dir("fe-ann-service-flags");
  const CliRun refused = RunShell(BinaryDir() + "/server/gonogo-server --data-dir " +
                                  dir.path().string() + " --fe-ann-distance-threshold -1");
  EXPECT_EQ(refused.exit_code, 2) << refused.out;
  EXPECT_NE(refused.out.find("--fe-ann-distance-threshold"), std::string::npos) << refused.out;
  const CliRun no_return = RunShell(BinaryDir() + "/server/gonogo-server --data-dir " +
                                    dir.path().string() +
                                    " --fe-ann-no-fallback --fe-ann-return-after-steps 10");
  EXPECT_EQ(no_return.exit_code, 2) << no_return.out;
  EXPECT_NE(no_return.out.find("--fe-ann-return-after-steps"), std::string::npos) << no_return.out;
  const CliRun negative_floor = RunShell(BinaryDir() + "/server/gonogo-server --data-dir " +
                                         dir.path().string() + " --fe-ann-pressure-floor-kpa -1");
  EXPECT_EQ(negative_floor.exit_code, 2) << negative_floor.out;
  EXPECT_NE(negative_floor.out.find("--fe-ann-pressure-floor-kpa"), std::string::npos)
      << negative_floor.out;
}

}  // namespace
}  // namespace gonogo::testing
