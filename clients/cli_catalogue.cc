// gonogo tiers | soils [MODEL] | health: what the server offers, and whether it serves.
#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <thread>

#include "clients/cli_commands.h"
#include "grpc/health/v1/health.grpc.pb.h"

namespace gonogo::cli {
namespace {

int RunTiers(Client& client) {
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
  return kExitOk;
}

std::string RangeText(const v1::SoilParameterInfo& p) {
  return std::string(p.min_open() ? "(" : "[") + FormatNumber(p.min()) + ", " +
         FormatNumber(p.max()) + (p.max_open() ? ")" : "]");
}

void PrintSoilModel(const v1::SoilModelInfo& m) {
  std::cout << "model " << m.name() << ": " << m.description() << "\n  source: " << m.source()
            << "\n";
  for (const auto& p : m.parameters()) {
    std::cout << "  " << std::left << std::setw(34) << p.name() << std::setw(11) << p.unit()
              << std::setw(18) << RangeText(p)
              << (p.has_default() ? "default " + FormatNumber(p.default_value()) : "required")
              << "  " << p.description() << "\n";
  }
}

void PrintCatalogue(const v1::ListSoilModelsResponse& resp) {
  std::cout << "\ncatalogue (use the name as --soil or in a soil table):\n";
  for (const auto& soil : resp.soils()) {
    std::string models, tiers;
    for (const auto& m : soil.models()) models += (models.empty() ? "" : ",") + m;
    for (const auto& t : soil.tiers()) tiers += (tiers.empty() ? "" : ",") + t;
    std::cout << "  " << std::left << std::setw(30) << soil.name() << std::setw(34) << models
              << (tiers.empty() ? "-" : tiers) << "\n";
  }
}

// Every model and the catalogue, or only the model named `only`.
int RunSoils(Client& client, const std::string& only) {
  grpc::ClientContext ctx;
  v1::ListSoilModelsResponse resp;
  const grpc::Status s = client.stub().ListSoilModels(&ctx, v1::ListSoilModelsRequest{}, &resp);
  if (!s.ok()) return Fail(s);
  bool found = false;
  for (const auto& m : resp.models()) {
    if (!only.empty() && m.name() != only) continue;
    found = true;
    PrintSoilModel(m);
  }
  if (!only.empty() && !found) throw UsageError("no soil model '" + only + "'");
  if (only.empty()) PrintCatalogue(resp);
  return kExitOk;
}

// gRPC's standard health check of the MobilityService: SERVING once the server takes work (under
// MPI, once every worker rank has checked in). With `wait_s` > 0, asks every half second until it
// serves or the time is up; a server not yet listening counts as not serving.
int RunHealth(Client& client, double wait_s) {
  using grpc::health::v1::HealthCheckResponse;
  auto health = grpc::health::v1::Health::NewStub(client.channel());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
  for (;;) {
    grpc::ClientContext ctx;
    ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    grpc::health::v1::HealthCheckRequest req;
    req.set_service("gonogo.v1.MobilityService");
    HealthCheckResponse resp;
    const grpc::Status s = health->Check(&ctx, req, &resp);
    const bool serving = s.ok() && resp.status() == HealthCheckResponse::SERVING;
    if (serving) {
      std::cout << "SERVING\n";
      return kExitOk;
    }
    if (std::chrono::steady_clock::now() >= deadline) {
      if (!s.ok()) return Fail(s);
      std::cout << HealthCheckResponse::ServingStatus_Name(resp.status()) << "\n";
      return kExitServer;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
}

}  // namespace

Command AddHealthCommand(CLI::App& parent) {
  auto wait_s = std::make_shared<double>(0.0);
  CLI::App* health = parent.add_subcommand(
      "health", "whether the server serves: SERVING once it takes work (under MPI, once every worker rank has checked in)");
  health->add_option("--wait", *wait_s, "keep asking until it serves or this many seconds pass, s")
      ->type_name("S")
      ->check(CLI::NonNegativeNumber.description(""));
  health->footer("Exit code 0 when SERVING, 3 when not (or not reachable).");
  return {health, [wait_s](Client& client) { return RunHealth(client, *wait_s); }};
}

Command AddTiersCommand(CLI::App& parent) {
  CLI::App* tiers =
      parent.add_subcommand("tiers", "the server's traction tiers: model, inputs, cost");
  return {tiers, [](Client& client) { return RunTiers(client); }};
}

Command AddSoilsCommand(CLI::App& parent) {
  auto model = std::make_shared<std::string>();
  CLI::App* soils = parent.add_subcommand(
      "soils", "soil models (parameter units, ranges, defaults) and the soil catalogue");
  soils->footer(
      "The catalogue lists each soil with the models it is calibrated for and the tiers reading "
      "it;\nits names go to --soil or into a soil table.");
  soils->add_option("MODEL", *model, "only this soil model's parameters");
  return {soils, [model](Client& client) { return RunSoils(client, *model); }};
}

}  // namespace gonogo::cli
