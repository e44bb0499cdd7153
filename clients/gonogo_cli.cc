// gonogo: command-line client of gonogo-server.
//
//   gonogo [--server HOST:PORT | --server @ENDPOINT_FILE] COMMAND [options]
//   gonogo map --cone-index ci.tif --elevation dem.tif --vehicle clients/vehicles/fed_alpha.json
//       --tier empirical --out out/
//   gonogo curve --tier empirical --vehicle clients/vehicles/fed_alpha.json --cone-index 300 --csv
//   gonogo COMMAND --help      a command's options with their units and defaults
//
// The commands live in cli_jobs.cc (map, jobs, watch, cancel, download), cli_curve.cc (curve,
// scalability), cli_catalogue.cc (tiers, soils, health) and cli_training.cc (models, train, dataset). Options are parsed by CLI11: a mistyped or
// unknown option, a missing required one or a value that does not convert is a usage error.
#include <CLI/CLI.hpp>
#include <iostream>
#include <string>
#include <vector>

#include "clients/cli_client.h"
#include "clients/cli_commands.h"

namespace {

using namespace gonogo::cli;

constexpr const char* kDefaultServer = "127.0.0.1:50051";

// The command the command line chose, "" when none.
std::string ChosenCommand(const CLI::App& app) {
  const auto chosen = app.get_subcommands();
  return chosen.empty() ? "" : chosen.front()->get_name();
}

// CLI11's message, except for what it did not expect: there the first unknown option (a typo
// must be named, not buried in a reversed list) or the unknown command.
std::string ParseErrorMessage(const CLI::App& app, const CLI::ParseError& e) {
  const std::vector<std::string> left = app.remaining(true);
  if (left.empty()) return e.what();
  if (ChosenCommand(app).empty()) return "unknown command '" + left.front() + "'";
  for (const std::string& arg : left) {
    if (arg.rfind("-", 0) == 0) return "unknown option " + arg.substr(0, arg.find('='));
  }
  return "unexpected argument '" + left.front() + "'";
}

// "gonogo: MESSAGE" and where the options are explained, on stderr; returns kExitUsage.
int UsageFailure(const CLI::App& app, const std::string& message) {
  const std::string command = ChosenCommand(app);
  std::cerr << "gonogo: " << message << "\nrun 'gonogo " << (command.empty() ? "" : command + " ")
            << "--help' for the options\n";
  return kExitUsage;
}

void AddGlobalOptions(CLI::App& app, std::string* server, Connection* connection) {
  app.add_option("--server", *server,
                 "gonogo-server's HOST:PORT, or @FILE holding it (and a token on its second line)")
      ->type_name("HOST:PORT|@FILE")
      ->envname("GONOGO_SERVER")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast)
      ->capture_default_str();
  app.add_option("--token", connection->token, "bearer token the server gave you")
      ->type_name("TOKEN")
      ->envname("GONOGO_TOKEN");
  app.add_option("--tls-ca", connection->tls_ca, "talk TLS, trusting the server certificate this CA signed")
      ->type_name("PEM")
      ->envname("GONOGO_TLS_CA")
      ->check(InputFile());
  app.add_option("--tls-cert", connection->tls_cert, "this client's certificate, for a server that asks")
      ->type_name("PEM")
      ->envname("GONOGO_TLS_CERT")
      ->check(InputFile());
  app.add_option("--tls-key", connection->tls_key, "the private key of --tls-cert")
      ->type_name("PEM")
      ->envname("GONOGO_TLS_KEY")
      ->check(InputFile());
  app.require_subcommand(1);
  app.get_formatter()->column_width(40);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Command-line client of gonogo-server: vehicle GO/NO-GO maps, traction curves.",
               "gonogo"};
  std::string server = kDefaultServer;
  Connection connection;
  AddGlobalOptions(app, &server, &connection);
  const std::vector<Command> commands = {
      AddMapCommand(app),         AddJobsCommand(app),     AddWatchCommand(app),
      AddCancelCommand(app),      AddDeleteCommand(app),   AddDownloadCommand(app), AddCurveCommand(app),
      AddScalabilityCommand(app), AddTiersCommand(app),    AddSoilsCommand(app),
      AddModelsCommand(app),      AddTrainCommand(app),    AddDatasetCommand(app),
      AddHealthCommand(app)};
  // After the subcommands: they would inherit it.
  app.footer(
      "Run gonogo COMMAND --help for a command's options.\n"
      "Exit codes: 0 done, 1 the job failed or was cancelled, 2 a usage error, 3 a server error.");
  try {
    app.parse(argc, argv);
    ResolveServer(server, &connection);
    Client client(connection);
    for (const Command& c : commands) {
      if (c.app->parsed()) return c.run(client);
    }
    return UsageFailure(app, "no command");
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    return UsageFailure(app, ParseErrorMessage(app, e));
  } catch (const UsageError& e) {
    return UsageFailure(app, e.what());
  }
}
