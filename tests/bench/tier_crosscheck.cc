// Cross-check of the two traction tiers on the same soils: bekker against empirical. A diagnostic,
// not a fit: neither tier is tuned to the other, and no cone index is made up.
//
//   build/tests/bench/gonogo-crosscheck-tiers [--cone-index SOIL=PA]...
//
// Wheel: the FED Alpha front wheel (tyre d 1.011 m, b 0.335 m, h 0.2178 m, deflection 0.0327 m,
// wheel load 14513 N), once at its inflation pressure of 241317 Pa (the bekker tier picks the
// rigid or the elastic mode against the soil's critical ground pressure) and once with the
// inflation pressure not given (the bekker tier's rigid wheel of diameter d). The empirical tier
// does not read the inflation pressure; it gets the same request in both cases. Every soil of the
// built-in Bekker library is run, the three snows included. Both tiers are swept over slips 0 to
// 1 by 0.01, as a map would request them, and D/W is read at 0.1, 0.2, 0.3 and 0.5.
//
// (a) Published cone index. Where a published cone index of a library soil is known, the
//     empirical curve at that cone index beside the bekker curve and the difference. The table
//     of published values, PublishedConeIndices(), is empty: no soil of the library was found with
//     a published cone index (solvers/terramech/README.md, "Cross-check: bekker against
//     empirical"). --cone-index SOIL=PA adds a value for one run (printed as given on the command
//     line); a row belongs in the table only with its source.
// (b) Equivalent cone index, for every soil: the cone index at which the empirical tier's D/W at
//     20 % slip equals the bekker tier's, by bisection on log(CI) over [1 kPa, 20 MPa] (the
//     empirical D/W grows with the cone index); "none" when the bekker D/W lies outside the
//     empirical range over that interval. Printed with the mobility number Bn at that cone index
//     and the empirical D/W there at 10 % and 50 % slip, to compare the shapes of the two curves.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "solvers/common/traction.h"
#include "solvers/terramech/bekker.h"
#include "solvers/terramech/bekker_soils.h"
#include "solvers/tiers/bekker_tier.h"
#include "solvers/terramech/brixius.h"
#include "solvers/tiers/empirical_tier.h"

using gonogo::TractionCurve;
using gonogo::TractionRequest;
using gonogo::TyreGeometry;

namespace {

constexpr double kWheelLoadN = 14513;
constexpr double kInflationPa = 241317;
constexpr double kMatchSlip = 0.2;
constexpr double kMinConeIndexPa = 1e3;
constexpr double kMaxConeIndexPa = 20e6;
constexpr double kReportSlips[] = {0.1, 0.2, 0.3, 0.5};

struct PublishedConeIndex {
  std::string soil;  // library name
  double cone_index_pa = 0;
  std::string source;
};

// Published cone indices of library soils, each with its source. None was found.
std::vector<PublishedConeIndex> PublishedConeIndices() { return {}; }

TyreGeometry FedAlphaFront(double inflation_pa) {
  TyreGeometry tyre;
  tyre.diameter_m = 1.011;
  tyre.width_m = 0.335;
  tyre.section_height_m = 0.2178;
  tyre.deflection_m = 0.0327;
  tyre.inflation_pressure_pa = inflation_pa;
  return tyre;
}

TractionRequest Request(const TyreGeometry& tyre, const std::string& soil, double cone_index_pa,
                        std::vector<double> slips) {
  TractionRequest request;
  request.soil.soil_name = soil;
  request.soil.cone_index_pa = cone_index_pa;
  request.tyre = tyre;
  request.wheel_load_n = kWheelLoadN;
  request.slips = std::move(slips);
  return request;
}

// D/W at each report slip; nullopt when the curve is immobile.
std::optional<std::vector<double>> RatiosAtReportSlips(const TractionCurve& curve) {
  if (curve.points.empty()) return std::nullopt;
  std::vector<double> ratios;
  for (double s : kReportSlips) ratios.push_back(curve.DrawbarPullAt(s) / kWheelLoadN);
  return ratios;
}

double EmpiricalRatio(const gonogo::tiers::EmpiricalTier& tier, const TyreGeometry& tyre,
                      double cone_index_pa, double slip) {
  const TractionCurve curve = tier.Compute(Request(tyre, "", cone_index_pa, {slip}));
  return curve.points.front().drawbar_pull_n / kWheelLoadN;
}

// The cone index in [kMinConeIndexPa, kMaxConeIndexPa] at which the empirical D/W at kMatchSlip
// equals `target`, by bisection on log(CI); nullopt outside the empirical range.
std::optional<double> EquivalentConeIndex(const gonogo::tiers::EmpiricalTier& tier,
                                          const TyreGeometry& tyre, double target) {
  double lo = kMinConeIndexPa;
  double hi = kMaxConeIndexPa;
  if (target < EmpiricalRatio(tier, tyre, lo, kMatchSlip) ||
      target > EmpiricalRatio(tier, tyre, hi, kMatchSlip)) {
    return std::nullopt;
  }
  for (int i = 0; i < 200 && hi / lo > 1 + 1e-12; ++i) {
    const double mid = std::sqrt(lo * hi);
    if (EmpiricalRatio(tier, tyre, mid, kMatchSlip) < target) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return std::sqrt(lo * hi);
}

std::string ModeName(const gonogo::BekkerParameters& soil, const TyreGeometry& tyre) {
  if (tyre.inflation_pressure_pa <= 0) return "rigid";
  const double p_gcr =
      gonogo::terramech::CriticalGroundPressurePa(soil, tyre.diameter_m, tyre.width_m, kWheelLoadN);
  return tyre.inflation_pressure_pa >= p_gcr ? "rigid" : "elastic";
}

void PrintPublishedComparison(const std::vector<PublishedConeIndex>& published,
                              const gonogo::tiers::BekkerTier& bekker,
                              const gonogo::tiers::EmpiricalTier& empirical,
                              const TyreGeometry& tyre) {
  if (published.empty()) {
    std::printf("  no library soil has a published cone index; nothing to compare\n");
    return;
  }
  std::printf("  %-29s %9s %-9s %7s %7s %7s %7s\n", "soil", "CI, kPa", "tier", "s=0.1", "s=0.2",
              "s=0.3", "s=0.5");
  const std::vector<double> sweep = TractionRequest::SlipSweep(0.01);
  for (const PublishedConeIndex& row : published) {
    const auto b = RatiosAtReportSlips(bekker.Compute(Request(tyre, row.soil, 0, sweep)));
    const auto e =
        RatiosAtReportSlips(empirical.Compute(Request(tyre, "", row.cone_index_pa, sweep)));
    const char* labels[] = {"bekker", "empirical", "diff"};
    for (int k = 0; k < 3; ++k) {
      std::printf("  %-29s %9.0f %-9s", k == 0 ? row.soil.c_str() : "", row.cone_index_pa * 1e-3,
                  labels[k]);
      for (size_t i = 0; i < std::size(kReportSlips); ++i) {
        if ((k != 1 && !b) || (k != 0 && !e)) {
          std::printf(" %7s", "-");
        } else if (k == 0) {
          std::printf(" %7.3f", (*b)[i]);
        } else if (k == 1) {
          std::printf(" %7.3f", (*e)[i]);
        } else {
          std::printf(" %+7.3f", (*b)[i] - (*e)[i]);
        }
      }
      std::printf("\n");
    }
    std::printf("  %-29s source: %s\n", "", row.source.c_str());
  }
}

void PrintEquivalentConeIndices(const gonogo::terramech::BekkerSoilLibrary& library,
                                const gonogo::tiers::BekkerTier& bekker,
                                const gonogo::tiers::EmpiricalTier& empirical,
                                const TyreGeometry& tyre) {
  std::printf("  %-29s %-7s %27s %9s %6s %13s\n", "", "", "bekker D/W at slip", "CI_eq", "Bn_eq",
              "empirical D/W");
  std::printf("  %-29s %-7s %6s %6s %6s %6s %9s %6s %6s %6s\n", "soil", "mode", "0.1", "0.2", "0.3",
              "0.5", "kPa", "", "0.1", "0.5");
  const std::vector<double> sweep = TractionRequest::SlipSweep(0.01);
  for (const gonogo::terramech::BekkerSoil& soil : library.Soils()) {
    std::printf("  %-29s %-7s", soil.name.c_str(), ModeName(soil.parameters, tyre).c_str());
    const auto b = RatiosAtReportSlips(bekker.Compute(Request(tyre, soil.name, 0, sweep)));
    if (!b) {
      std::printf(" %27s %9s\n", "cannot carry", "-");
      continue;
    }
    for (double ratio : *b) std::printf(" %6.3f", ratio);
    const std::optional<double> ci = EquivalentConeIndex(empirical, tyre, (*b)[1]);
    if (!ci) {
      std::printf(" %9s\n", "none");
      continue;
    }
    std::printf(" %9.1f %6.2f %6.3f %6.3f\n", *ci * 1e-3,
                gonogo::terramech::MobilityNumber(*ci, tyre, kWheelLoadN),
                EmpiricalRatio(empirical, tyre, *ci, 0.1),
                EmpiricalRatio(empirical, tyre, *ci, 0.5));
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<PublishedConeIndex> published = PublishedConeIndices();
  CLI::App app(
      "Cross-check of the two traction tiers on the same soils: bekker against empirical, on the "
      "FED Alpha front wheel, (a) at a published cone index and (b) at the equivalent cone index "
      "of every library soil (see the comment at the top of tests/bench/tier_crosscheck.cc).",
      "gonogo-crosscheck-tiers");
  app.add_option_function<std::vector<std::string>>(
         "--cone-index",
         [&published](const std::vector<std::string>& pairs) {
           for (const std::string& pair : pairs) {
             const size_t eq = pair.find('=');
             published.push_back(
                 {pair.substr(0, eq), std::stod(pair.substr(eq + 1)), "given on the command line"});
           }
         },
         "a published cone index of a library soil for this run, Pa (repeatable); a row belongs "
         "in PublishedConeIndices() only with its source")
      ->type_name("SOIL=PA")
      ->allow_extra_args(false)
      ->check(CLI::Validator(
          [](std::string& pair) {
            const size_t eq = pair.find('=');
            double pa = 0;
            if (eq == 0 || eq == std::string::npos ||
                !CLI::detail::lexical_cast(pair.substr(eq + 1), pa) || !std::isfinite(pa) ||
                pa <= 0) {
              return "needs SOIL=PA with a cone index PA > 0, got '" + pair + "'";
            }
            return std::string();
          },
          "", "SOIL=PA"));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  const auto& library = gonogo::terramech::BekkerSoilLibrary::Builtin();
  const gonogo::tiers::BekkerTier bekker;
  const gonogo::tiers::EmpiricalTier empirical;

  std::printf("FED Alpha front wheel: d 1.011 m, b 0.335 m, h 0.2178 m, delta 0.0327 m, W %.0f N\n",
              kWheelLoadN);
  std::printf("empirical D/W at s = 0.2: %.3f at CI = 1 kPa, %.3f at CI = 20 MPa\n",
              EmpiricalRatio(empirical, FedAlphaFront(0), kMinConeIndexPa, kMatchSlip),
              EmpiricalRatio(empirical, FedAlphaFront(0), kMaxConeIndexPa, kMatchSlip));
  for (double inflation_pa : {kInflationPa, 0.0}) {
    const TyreGeometry tyre = FedAlphaFront(inflation_pa);
    std::printf("\n== inflation %s ==\n",
                inflation_pa > 0 ? "241317 Pa (35 psi)" : "not given: bekker rigid wheel");
    std::printf("(a) at a published cone index\n");
    PrintPublishedComparison(published, bekker, empirical, tyre);
    std::printf("(b) equivalent cone index: empirical D/W(0.2) = bekker D/W(0.2)\n");
    PrintEquivalentConeIndices(library, bekker, empirical, tyre);
  }
  return 0;
}
