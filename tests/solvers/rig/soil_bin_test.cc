// One procedure over any soil bin: the drawbar-pull procedure of seed 001 (shortened) runs over FE
// bins built from the material registry by name, with Drucker-Prager and with linear elasticity
// of the same stiffness. Plastic flow only adds compliance, so the elastic soil sinks less and
// resists rolling less; the by-name Drucker-Prager bin is the fe-classic bin, bit for bit.
#include "solvers/rig/soil_bin.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/material/registry.h"
#include "solvers/rig/fe_soil_bin.h"
#include "solvers/rig/fe_soils.h"
#include "solvers/rig/wheel_rig.h"

namespace gonogo::rig {
namespace {


// The 0.5-scale tyre of seed 001 Table 4 as a rigid wheel.
RigWheel HalfScaleWheel() { return {0.2525, 0.167, 3359}; }

// A coarse bin and a shortened procedure: seconds, not minutes.
RigOptions Coarse() {
  RigOptions o;
  o.elements_per_radius = 3;
  o.threads = 1;
  return o;
}

DrawbarPullProcedure Shortened() {
  DrawbarPullProcedure p;
  p.gravity_settle_s = 0.05;
  p.self_propelled_s = 0.15;
  p.speed_ramp_up_s = 0.05;
  p.slip_ramp_s = 0.2;
  return p;
}

// Just long enough to pass every phase, for identities.
DrawbarPullProcedure Brief() {
  DrawbarPullProcedure p;
  p.gravity_settle_s = 0.02;
  p.load_settle_s = 0.04;
  p.self_propelled_s = 0.04;
  p.speed_ramp_up_s = 0.02;
  p.slip_ramp_s = 0.04;
  return p;
}

const FeSoil& DrySand() { return *FeSoilLibrary::Builtin().Find("lll_dry_sand"); }

// lll_dry_sand by name: `model` with the row's elastic constants (and strength, for
// drucker-prager), the row's density, and the rim contact of its strength.
FeSoilBinFactory DrySandBins(const std::string& model) {
  material::MaterialRegistry registry;
  material::RegisterBuiltinMaterials(registry);
  const FeSoil& sand = DrySand();
  FeBinSoilSpec spec;
  spec.label = sand.name;
  spec.model_name = model;
  spec.parameters = {{"young_pa", sand.strength.young_pa}, {"poisson", sand.strength.poisson}};
  if (model == "drucker-prager") {
    spec.parameters["cohesion_pa"] = sand.strength.cohesion_pa;
    spec.parameters["friction_angle_deg"] = sand.strength.friction_angle_deg;
    spec.parameters["dilation_angle_deg"] = sand.strength.dilation_angle_deg;
  }
  spec.density_kg_m3 = sand.density_kg_m3;
  spec.wheel_friction_coefficient =
      std::tan(units::DegreesToRadians(sand.strength.friction_angle_deg));
  spec.wheel_adhesion_pa = sand.strength.cohesion_pa;
  FeBinOptions options;
  options.threads = Coarse().threads;
  return FeSoilBinFactory(MakeFeBinSoil(registry, spec), options);
}

// Means over the last half of a phase.
struct PhaseMean {
  double sinkage_m = 0, drawbar_pull_n = 0, torque_nm = 0, vertical_force_n = 0;
};
PhaseMean MeanOfPhase(const RigRun& run, int phase) {
  double first = -1, last = -1;
  for (const RigSample& s : run.samples) {
    if (s.phase != phase) continue;
    if (first < 0) first = s.time_s;
    last = s.time_s;
  }
  PhaseMean m;
  int n = 0;
  for (const RigSample& s : run.samples) {
    if (s.phase != phase || s.time_s < 0.5 * (first + last)) continue;
    m.sinkage_m += s.sinkage_m;
    m.drawbar_pull_n += s.drawbar_pull_n;
    m.torque_nm += s.torque_nm;
    m.vertical_force_n += s.vertical_force_n;
    ++n;
  }
  EXPECT_GT(n, 2) << "phase " << phase;
  m.sinkage_m /= n;
  m.drawbar_pull_n /= n;
  m.torque_nm /= n;
  m.vertical_force_n /= n;
  return m;
}

TEST(SoilBinTest, TheProcedureRunsOverDruckerPragerAndLinearElasticBinsByName) {
  const RigWheel wheel = HalfScaleWheel();
  const FeSoilBinFactory plastic = DrySandBins("drucker-prager");
  const FeSoilBinFactory elastic = DrySandBins("linear-elastic");
  EXPECT_EQ(plastic.Describe(), "fe drucker-prager (lll_dry_sand)");
  EXPECT_EQ(elastic.Describe(), "fe linear-elastic (lll_dry_sand)");
  const RigRun dp = RunDrawbarPullTest(plastic, wheel, Shortened(), Coarse());
  const RigRun le = RunDrawbarPullTest(elastic, wheel, Shortened(), Coarse());
  for (const RigRun* run : {&dp, &le}) {
    for (const RigSample& s : run->samples) {
      ASSERT_TRUE(std::isfinite(s.drawbar_pull_n) && std::isfinite(s.torque_nm) &&
                  std::isfinite(s.sinkage_m));
    }
  }
  for (int phase : {2, 3, 4}) {
    const PhaseMean p = MeanOfPhase(dp, phase), e = MeanOfPhase(le, phase);
    std::printf("phase %d: DP z %.4f m D %.0f N T %.1f N m Fz %.0f N | LE z %.4f m D %.0f N "
                "T %.1f N m Fz %.0f N\n",
                phase, p.sinkage_m, p.drawbar_pull_n, p.torque_nm, p.vertical_force_n,
                e.sinkage_m, e.drawbar_pull_n, e.torque_nm, e.vertical_force_n);
  }
  const double w = wheel.load_n, r = wheel.radius_m;
  const PhaseMean dp_load = MeanOfPhase(dp, 2), le_load = MeanOfPhase(le, 2);
  const PhaseMean dp_rolling = MeanOfPhase(dp, 3), le_rolling = MeanOfPhase(le, 3);
  const PhaseMean dp_ramp = MeanOfPhase(dp, 4), le_ramp = MeanOfPhase(le, 4);
  // Plastic flow only adds compliance: under the same load history the Drucker-Prager soil sinks
  // more than the elastic soil of the same E and nu.
  EXPECT_GT(dp_load.sinkage_m, 1.2 * le_load.sinkage_m);
  EXPECT_GT(dp_rolling.sinkage_m, 2 * le_rolling.sinkage_m);
  // Slip sinkage is plastic: the elastic soil keeps its zero-slip sinkage through the slip ramp,
  // the plastic one digs in.
  EXPECT_NEAR(le_ramp.sinkage_m, le_rolling.sinkage_m, 0.2 * le_rolling.sinkage_m);
  EXPECT_GT(dp_ramp.sinkage_m, 1.3 * dp_rolling.sinkage_m);
  // Motion resistance at zero slip, T/R - D, is the work of making the rut (Wong 2008, sec. 2.7):
  // the elastic soil gives back what the wheel stores in it.
  const double dp_resistance = dp_rolling.torque_nm / r - dp_rolling.drawbar_pull_n;
  const double le_resistance = le_rolling.torque_nm / r - le_rolling.drawbar_pull_n;
  EXPECT_GT(dp_resistance, 0.1 * w);
  EXPECT_LT(std::abs(le_resistance), 0.05 * w);
  // On both soils the driven wheel pulls once it slips.
  EXPECT_GT(dp_ramp.drawbar_pull_n, dp_rolling.drawbar_pull_n + 0.05 * w);
  EXPECT_GT(le_ramp.drawbar_pull_n, le_rolling.drawbar_pull_n + 0.05 * w);
}

TEST(SoilBinTest, AnUnknownModelNameListsTheKnownOnes) {
  FeBinSoilSpec spec;
  spec.model_name = "cam-clay";
  spec.density_kg_m3 = 1500;
  material::MaterialRegistry registry;
  material::RegisterBuiltinMaterials(registry);
  try {
    MakeFeBinSoil(registry, spec);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "material");
    EXPECT_NE(std::string(e.what()).find("linear-elastic"), std::string::npos) << e.what();
  }
}

TEST(SoilBinTest, DruckerPragerByNameIsTheFeClassicBin) {
  const RigRun by_name = RunDrawbarPullTest(DrySandBins("drucker-prager"), HalfScaleWheel(),
                                            Brief(), Coarse());
  const RigRun classic = RunDrawbarPullTest(DrySand(), HalfScaleWheel(), Brief(), Coarse());
  ASSERT_EQ(by_name.samples.size(), classic.samples.size());
  for (size_t k = 0; k < by_name.samples.size(); ++k) {
    EXPECT_EQ(by_name.samples[k].drawbar_pull_n, classic.samples[k].drawbar_pull_n) << k;
    EXPECT_EQ(by_name.samples[k].torque_nm, classic.samples[k].torque_nm) << k;
    EXPECT_EQ(by_name.samples[k].sinkage_m, classic.samples[k].sinkage_m) << k;
  }
}

}  // namespace
}  // namespace gonogo::rig
