// The periodic DE RVE behind the constitutive seam (material::ConstitutiveModel): one RVE per
// integration point, its state the whole RVE. A batch runs on OpenMP threads, one RVE per thread,
// each RVE serial inside, so results do not depend on the thread count.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "solvers/dem/rve/rve.h"
#include "solvers/material/constitutive.h"

namespace gonogo::dem::rve {

struct RveMaterialParams {
  RveParams rve;                     // the template RVE every point starts from
  int min_steps_per_increment = 20;  // DE steps spreading one increment (more if the rate cap asks)
  int relax_steps = 50;              // DE steps with the cell fixed after the increment
  // Larger components of the increment's stretch U - I (I + dH = R U, Rve::IncrementStrain) are
  // refused (cut the step); the rotation R may be of any size short of a half turn.
  double max_strain_increment = 0.01;
  int batch_threads = 1;  // OpenMP threads over the points of a batch

  void Validate() const;
};

class RveState : public material::MaterialState {
 public:
  explicit RveState(Rve rve) : rve_(std::move(rve)) {}
  std::unique_ptr<material::MaterialState> Clone() const override;
  std::string Serialize() const override { return rve_.Save(); }
  const Rve& rve() const { return rve_; }
  Rve& rve() { return rve_; }

 private:
  Rve rve_;
};

class RveMaterial : public material::ConstitutiveModel {
 public:
  // Generates and consolidates the template RVE (seconds for 500 grains).
  explicit RveMaterial(const RveMaterialParams& params);
  // Starts every point from a given consolidated RVE instead.
  RveMaterial(const RveMaterialParams& params, Rve initial);

  std::string Name() const override { return "dem-rve"; }
  std::unique_ptr<material::MaterialState> InitialState() const override;
  std::unique_ptr<material::MaterialState> RestoreState(const std::string& bytes) const override;
  std::vector<material::PointResponse> Update(const std::vector<material::PointIncrement>& increments,
                                              bool want_tangent) const override;

  const RveMaterialParams& params() const { return params_; }
  // The consolidated RVE every point starts from (InitialState is a copy of it).
  const Rve& initial() const { return initial_; }

 private:
  material::PointResponse UpdateOne(const material::PointIncrement& increment,
                                    bool want_tangent) const;

  RveMaterialParams params_;
  Rve initial_;
};

}  // namespace gonogo::dem::rve
