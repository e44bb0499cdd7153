// The subcommands of `gonogo`. Each Add*Command declares a subcommand of `parent` with its options
// (names, units, defaults, which exclude or need which) and returns what runs it once the command
// line has parsed. A runner returns the exit code (cli_client.h) or throws UsageError.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <optional>
#include <string>

#include "clients/cli_client.h"

namespace gonogo::cli {

// Checks whose own text would only clutter --help (the option's type name and description say it).
inline CLI::Validator InputFile() { return CLI::Validator(CLI::ExistingFile).description(""); }
inline CLI::Validator Fraction() { return CLI::Validator(CLI::Range(0.0, 1.0)).description(""); }

struct Command {
  CLI::App* app;                    // the subcommand, owned by its parent
  std::function<int(Client&)> run;  // runs it against the server
};

// Jobs (cli_jobs.cc).
Command AddMapCommand(CLI::App& parent);
Command AddJobsCommand(CLI::App& parent);
Command AddWatchCommand(CLI::App& parent);
Command AddCancelCommand(CLI::App& parent);
Command AddDeleteCommand(CLI::App& parent);
Command AddDownloadCommand(CLI::App& parent);

// Traction curves (cli_curve.cc).
Command AddCurveCommand(CLI::App& parent);
Command AddScalabilityCommand(CLI::App& parent);

// What the server offers (cli_catalogue.cc).
Command AddTiersCommand(CLI::App& parent);
Command AddSoilsCommand(CLI::App& parent);
Command AddHealthCommand(CLI::App& parent);

// The fe-ann tier's models and their training data (cli_training.cc).
Command AddModelsCommand(CLI::App& parent);
Command AddTrainCommand(CLI::App& parent);
Command AddDatasetCommand(CLI::App& parent);

// The fe-ann surrogate options that `gonogo curve` and `gonogo map` share (cli_training.cc), in
// the group "Surrogate (fe-ann)": --model ID, and the request's guard over the server's:
// --distance-threshold D, --spread-threshold S, --pressure-floor-kpa P, --fallback on|off,
// --return-after-steps N.
struct SurrogateOptions {
  std::string model;  // empty: the soil's best
  std::optional<double> distance_threshold;
  std::optional<double> spread_threshold;
  std::optional<double> pressure_floor_kpa;
  std::string fallback;  // "on", "off", or empty: the server's
  std::optional<int> return_after_steps;
};
void AddSurrogateOptions(CLI::App& app, SurrogateOptions* surrogate, const std::string& model_help);
// The guard's fields given, and only those (the server checks their values).
v1::SurrogateGuard GuardFromOptions(const SurrogateOptions& surrogate);

}  // namespace gonogo::cli
