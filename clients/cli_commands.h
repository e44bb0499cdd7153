// The subcommands of `gonogo`. Each Add*Command declares a subcommand of `parent` with its options
// (names, units, defaults, which exclude or need which) and returns what runs it once the command
// line has parsed. A runner returns the exit code (cli_client.h) or throws UsageError.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

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

}  // namespace gonogo::cli
