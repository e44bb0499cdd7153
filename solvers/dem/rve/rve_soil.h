// The production DE RVE material, built from a soil description: a validated
// `dem-hertz-mindlin` parameter set (solvers/common/soil_model.h, seed 000's grain law) plus the
// DE-side numerics of the FE-DE bridge becomes an RveMaterial (rve_material.h), and "dem-rve" is
// registered under that name for the FE solver (solvers/material/registry.h).
//
//   SoilParameters soil{"dem-hertz-mindlin", {{"friction", 0.5}}};  // the rest: defaults
//   RveMaterialParams params = RveMaterialParamsFromSoil(soil, RveNumerics{});
//   std::shared_ptr<const RveMaterial> material = SharedRveMaterial(params);  // seconds, once
//   double rho_kg_m3 = ConsolidatedBulkDensityKgM3(*material);  // the FE soil's density
//
// Generating and consolidating a template RVE takes seconds (about 2 s for 500 grains, under
// half a second for 100, on one core), so templates are generated once per distinct parameter
// set per process and every material starts its points from a copy.
#pragma once

#include <memory>
#include <string>

#include "solvers/common/soil_model.h"
#include "solvers/dem/rve/rve.h"
#include "solvers/dem/rve/rve_material.h"
#include "solvers/material/registry.h"

namespace gonogo::dem::rve {

// How the DE side answers an FE increment: numerics of the bridge, not properties of the soil.
struct RveNumerics {
  int min_steps_per_increment = 20;  // DE steps, at least, spreading one FE increment (-)
  int relax_steps = 50;              // DE steps with the cell held after the increment (-)
  // Largest component of the increment's stretch U - I (-) a point accepts; larger ones fail
  // the point so the FE solver cuts its step.
  double max_strain_increment = 0.01;
  // Inertial number I = rate d sqrt(rho / p) (-) the DE strain rate is capped at (GDR MiDi 2004):
  // sets how many DE steps an increment takes beyond min_steps_per_increment.
  double max_inertial_number = 1e-3;
  unsigned seed = 1;  // random placement of the template's grains (-)

  // Throws InputError(field_prefix + field, reason) for a value out of range.
  void Validate(const std::string& field_prefix) const;
};

// The soil parameter set's model; the only one RveMaterialParamsFromSoil maps.
inline constexpr char kRveSoilModel[] = "dem-hertz-mindlin";

// Maps a `dem-hertz-mindlin` set onto the RVE (README.md, "From a soil description"): grain law
// E, nu, mu, beta, eta and density, mean radius, grain count, initial solid fraction and
// consolidation pressure; the numerics as given; everything else keeps its RveParams default
// (restitution 0.5, radius spread 0.2, frictionless consolidation, one thread per RVE, one batch
// thread). The set is validated first (missing parameters take their defaults). Throws
// InputError naming `field` + "." + parameter for a set of another model ("<field>.model"), a
// value out of its range, a grain count that is not an integer ("<field>.grains_per_rve") or
// bad numerics.
RveMaterialParams RveMaterialParamsFromSoil(const SoilParameters& soil, const RveNumerics& numerics,
                                            const std::string& field = "soil");

// The consolidated template RVE of `params`: generated (Rve::Generate) on the first call for a
// parameter set and shared by every later call with an equal one (every field of RveParams is
// part of the key). Thread-safe: concurrent callers of one set wait for the one generation;
// different sets generate concurrently. A failed generation throws to every caller waiting on it
// and is not kept, so a later call tries again. Templates live until the process ends (about
// 660 bytes per grain). Costs seconds on the first call of a set (see the file comment).
std::shared_ptr<const Rve> SharedRveTemplate(const RveParams& params);

// An RveMaterial of `params` whose points start from a copy of SharedRveTemplate(params.rve).
// Thread-safe; costs a template generation only on the first call of a parameter set.
std::shared_ptr<const RveMaterial> SharedRveMaterial(const RveMaterialParams& params);

// Bulk density of the consolidated packing, kg/m^3: grain density x solid fraction of the
// material's initial RVE. The reference density of an FE soil of this material.
double ConsolidatedBulkDensityKgM3(const RveMaterial& material);

// Registers "dem-rve": an RveMaterial over the shared template (as SharedRveMaterial) built from
// a flat parameter map whose keys are the dem-hertz-mindlin parameters (young_pa, poisson,
// friction, rolling_stiffness, rolling_limit, particle_radius_m, density_kg_m3, grains_per_rve,
// consolidation_pressure_pa, initial_solid_fraction; missing ones take the soil model's
// defaults, seed 000's), the RveNumerics fields (min_steps_per_increment, relax_steps,
// max_strain_increment, max_inertial_number, seed; missing ones take their defaults) and
// batch_threads (OpenMP threads over a batch's points, default 1). Unknown keys, values out of
// range and non-integers where an integer is due throw InputError("material.<key>", ...). The
// example parameters are a cheap configuration (100 grains, 20 + 30 DE steps per increment) for
// the contract test.
void RegisterRveMaterial(material::MaterialRegistry& registry);

}  // namespace gonogo::dem::rve
