// The wheel and soil options that `gonogo curve` and `gonogo scalability` share, and the request
// parts they become.
//
//   wheel: --vehicle FILE [--axle N] | --wheel-diameter M --wheel-width M --wheel-load N
//          [--section-height M] [--deflection M] [--rolling-radius M] [--inflation-pressure-kpa
//          KPA]
//   soil:  at least one of --cone-index KPA, --soil NAME, and --bekker ... or --soil-params ...
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "clients/cli_client.h"

namespace gonogo::cli {

struct WheelOptions {
  std::string vehicle_file;  // a vehicle JSON (clients/vehicles); empty: the wheel options below
  int axle = 1;              // axle of the vehicle, 1 = front
  std::optional<double> diameter_m;
  std::optional<double> width_m;
  std::optional<double> wheel_load_n;
  std::optional<double> section_height_m;  // absent: a rigid wheel (d/4 is sent)
  double deflection_m = 0;
  double rolling_radius_m = 0;        // 0: d/2 - deflection
  double inflation_pressure_kpa = 0;  // 0: not given
};

struct SoilOptions {
  std::optional<double> cone_index_kpa;
  std::string soil_name;    // soil catalogue name (`gonogo soils`)
  std::string bekker;       // "n=N,kc=KC,kphi=KPHI,c=C,phi_deg=PHI,K=K"
  std::string soil_params;  // "MODEL:NAME=VALUE,..."
};

// Declares the wheel options on `app` in the group "Wheel"; `--vehicle` excludes the wheel's own.
void AddWheelOptions(CLI::App& app, WheelOptions* wheel);

// Declares the soil options on `app` in the group "Soil"; `--bekker` excludes `--soil-params`.
void AddSoilOptions(CLI::App& app, SoilOptions* soil);

// The tyre and its wheel load, N: the vehicle axle's (its load shared by the axle's wheels) or the
// wheel given. Throws UsageError when the axle does not exist or a wheel dimension is missing.
void WheelFromOptions(const WheelOptions& wheel, v1::Tyre* tyre, double* wheel_load_n);

// The soil state; throws UsageError when no soil is given or a parameter list is malformed.
v1::SoilState SoilFromOptions(const SoilOptions& soil);

}  // namespace gonogo::cli
