// The FE soil bin: explicit total-Lagrangian hexahedra (solvers/fe) over any constitutive model,
// given as a model object or by name from the material registry (solvers/material/registry.h).
// The rigid wheel touches the top surface nodes through a penalty contact with Coulomb friction
// and adhesion (wheel_contact.h); flat tools prescribe the velocities of, or load, the surface
// nodes they cover.
//
//   material::MaterialRegistry registry;
//   material::RegisterBuiltinMaterials(registry);
//   FeSoilBinFactory bins(MakeFeBinSoil(registry, {"sand", "linear-elastic",
//                         {{"young_pa", 10e6}, {"poisson", 0.3}}, 1600, 0.6, 0}), FeBinOptions{});
//   RigRun run = RunDrawbarPullTest(bins, wheel, DrawbarPullProcedure{}, RigOptions{});
//
// Wheel bins mesh the half y >= 0 (y = 0 a symmetry plane), plate bins a quarter, turning-tool
// bins the whole box; floors are fixed, side walls and symmetry planes on rollers. Reactions are
// scaled up to the whole wheel or tool.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "solvers/material/constitutive.h"
#include "solvers/material/registry.h"
#include "solvers/rig/fe_soils.h"
#include "solvers/rig/soil_bin.h"

namespace gonogo::rig {

// The soil of an FE bin: a constitutive model, its density and the rim-soil contact.
struct FeBinSoil {
  std::string label;  // for messages, e.g. the soil library row
  std::shared_ptr<const material::ConstitutiveModel> model;
  double density_kg_m3 = 0;
  double wheel_friction_coefficient = 0;  // mu of the rim-soil contact, -, >= 0
  double wheel_adhesion_pa = 0;           // c_a of the rim-soil contact, Pa, >= 0
  // The initial state of a point whose element's centre lies depth_m below the surface, as the
  // model's MaterialState bytes (an initial stress field: RVEs unloaded to the stress of their
  // depth). Empty: every point starts from the model's InitialState. Called once per distinct
  // depth of a bin.
  std::function<std::string(double depth_m)> initial_state_at_depth;
  // Throws InputError naming field_prefix + the field.
  void Validate(const std::string& field_prefix) const;
};

// The same by model name, as a request or a soil table carries it.
struct FeBinSoilSpec {
  std::string label;
  std::string model_name;  // a registry name: "drucker-prager", "linear-elastic", ...
  material::ParameterMap parameters;
  double density_kg_m3 = 0;
  double wheel_friction_coefficient = 0;
  double wheel_adhesion_pa = 0;
};

// Throws InputError ("material", "material.<key>", "soil.<field>") for an unknown model, a bad
// parameter or a bad density or contact value.
FeBinSoil MakeFeBinSoil(const material::MaterialRegistry& registry, const FeBinSoilSpec& spec);

// The fe-classic soil: Drucker-Prager of soil.strength (triaxial-compression match), and the rim
// contact of the soil's own strength, mu = tan(phi), c_a = c.
FeBinSoil FeBinSoilFromFeSoil(const FeSoil& soil);

// FE numerics (fe::ExplicitOptions, which validates them).
struct FeBinOptions {
  double hourglass_coefficient = 0.05;
  double hourglass_viscosity = 0.1;
  double time_step_safety = 0.5;  // of the critical step, for the elements and the contact
  int threads = 1;                // OpenMP threads of one bin
  // Quasi-static runs over an expensive closure (a DE RVE per point): > 0 lifts the bin's stable
  // step to this by mass scaling (fe::ExplicitOptions::mass_scaling; weight is kept), s. 0: the
  // stable step of the physical masses.
  double target_time_step_s = 0;
};

class FeSoilBinFactory : public SoilBinFactory {
 public:
  // Throws InputError for an invalid soil.
  FeSoilBinFactory(FeBinSoil soil, FeBinOptions options);

  std::string Describe() const override;
  std::unique_ptr<SoilBin> MakeWheelBin(const WheelBinLayout& layout) const override;
  std::unique_ptr<SoilBin> MakeToolBin(const ToolBinLayout& layout) const override;

  const FeBinSoil& soil() const { return soil_; }

 private:
  FeBinSoil soil_;
  FeBinOptions options_;
};

}  // namespace gonogo::rig
