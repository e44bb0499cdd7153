#include "solvers/rig/fe_soil_bin.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <stdexcept>
#include <utility>
#include <vector>

#include "solvers/common/byte_stream.h"
#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/fe/explicit_solver.h"
#include "solvers/fe/mesh.h"
#include "solvers/material/drucker_prager.h"
#include "solvers/rig/wheel_contact.h"

namespace gonogo::rig {
namespace {

using units::kPi;

// The surface nodes a flat tool covers, and how it last moved them.
struct ToolNodes {
  std::vector<int> nodes;
  std::vector<double> areas_m2;
  FlatToolDrive drive;
  double speed_before_m_s = 0;  // vertical speed of the step before the last, for its inertia
  bool grips = false;           // x and y of its nodes are prescribed
  bool pushes = false;          // z of its nodes is prescribed
};

constexpr char kBinStateTag[9] = "GNGFEB01";

class FeSoilBin : public SoilBin {
 public:
  // `modelled_fraction`: the part of the whole wheel or tool the mesh holds (symmetry).
  FeSoilBin(std::unique_ptr<fe::ExplicitSolver> solver, double settling_damping_per_s,
            double stable_time_step_s, double modelled_fraction, bool tools_allowed)
      : solver_(std::move(solver)),
        settling_damping_per_s_(settling_damping_per_s),
        stable_time_step_s_(stable_time_step_s),
        whole_per_modelled_(1.0 / modelled_fraction),
        tools_allowed_(tools_allowed) {
    TopSurfaceNodes(solver_->mesh(), &surface_, &areas_m2_);
  }

  fe::ExplicitSolver& solver() { return *solver_; }
  const std::vector<int>& surface() const { return surface_; }
  const std::vector<double>& surface_areas_m2() const { return areas_m2_; }
  void set_stable_time_step_s(double dt_s) { stable_time_step_s_ = dt_s; }
  void set_wheel(std::unique_ptr<WheelContact> wheel) { wheel_ = std::move(wheel); }
  // Mass scaling that lifts the stable step to `target_time_step_s` (no change when it is already
  // larger): factor (target / dt)^2 on the masses, so the step and the settling rate (the first
  // vertical mode's, proportional to the wave speed) move by its square root.
  void ScaleMassToTimeStep(double target_time_step_s) {
    if (!(target_time_step_s > stable_time_step_s_)) return;
    const double ratio = target_time_step_s / stable_time_step_s_;
    solver_->SetMassScaling(solver_->mass_scaling() * ratio * ratio);
    settling_damping_per_s_ /= ratio;
    solver_->set_mass_damping_per_s(settling_damping_per_s_);
    stable_time_step_s_ = target_time_step_s;
  }

  SoilBinSize Size() const override {
    return {solver_->mesh().num_elements(), solver_->mesh().num_nodes()};
  }
  double StableTimeStepS() const override { return stable_time_step_s_; }
  double time_s() const override { return solver_->time_s(); }
  double SettlingDampingPerS() const override { return settling_damping_per_s_; }
  void SetDampingPerS(double damping_per_s) override {
    solver_->set_mass_damping_per_s(damping_per_s);
  }

  // Wheel bins only: the solver's state, the contact's slip histories and the last step.
  std::string SaveState() const override {
    if (wheel_ == nullptr) throw std::logic_error("only wheel bins checkpoint");
    ByteWriter out;
    out.PutTag(kBinStateTag);
    out.PutBlob(solver_->SaveState());
    out.PutVector(wheel_->slip_history_m());
    out.Put(last_dt_s_);
    return out.Take();
  }
  void RestoreState(const std::string& bytes) override {
    if (wheel_ == nullptr) throw std::logic_error("only wheel bins checkpoint");
    ByteReader in(bytes);
    in.ExpectTag(kBinStateTag);
    std::string solver_state;
    in.GetBlob(solver_state);
    std::vector<Vec3> slip_history;
    in.GetVector(slip_history, wheel_->surface_nodes().size());
    double last_dt_s = 0;
    in.Get(last_dt_s);
    Require(in.AtEnd(), "state", "trailing bytes after the bin state");
    solver_->RestoreState(solver_state);  // checks the mesh, changes nothing on failure
    wheel_->RestoreSlipHistory(std::move(slip_history));
    last_dt_s_ = last_dt_s;
  }
  void WritePointCheckpoint(const std::string& directory, std::uint64_t generation) override {
    solver_->mutable_material_points().WriteCheckpoint(directory, generation);
  }
  void ReadPointCheckpoint(const std::string& directory, std::uint64_t generation) override {
    solver_->mutable_material_points().ReadCheckpoint(directory, generation);
  }

  BinStepStatus Step(double dt_s) override {
    const fe::StepStatus status = solver_->Step(dt_s);
    if (status.ok) last_dt_s_ = dt_s;
    return {status.ok, status.reason};
  }

  WheelLoad ApplyWheel(const WheelMotion& wheel, double dt_s) override {
    if (wheel_ == nullptr) throw std::logic_error("ApplyWheel on an FE bin made for a flat tool");
    auto& f_ext = solver_->external_forces_n();
    for (int n : surface_) f_ext[n].setZero();
    WheelLoad load = wheel_->Apply(wheel, *solver_, dt_s);
    load.force_n *= whole_per_modelled_;
    load.moment_y_nm *= whole_per_modelled_;
    return load;
  }

  FlatTool AttachFlatTool(double inner_radius_m, double outer_radius_m) override;
  void DriveFlatTool(int tool, const FlatToolDrive& drive) override;
  FlatToolLoad FlatToolReaction(int tool) const override;

 private:
  const ToolNodes& Tool(int tool) const {
    if (tool < 0 || tool >= static_cast<int>(tools_.size())) {
      throw std::out_of_range("no flat tool " + std::to_string(tool) + " on this bin");
    }
    return tools_[tool];
  }

  std::unique_ptr<fe::ExplicitSolver> solver_;
  double settling_damping_per_s_;
  double stable_time_step_s_;
  double whole_per_modelled_;
  bool tools_allowed_;
  double last_dt_s_ = 0;
  std::vector<int> surface_;         // top surface nodes
  std::vector<double> areas_m2_;     // their tributary areas
  std::unique_ptr<WheelContact> wheel_;
  std::vector<ToolNodes> tools_;
};

FlatTool FeSoilBin::AttachFlatTool(double inner_radius_m, double outer_radius_m) {
  if (!tools_allowed_) throw std::logic_error("a flat tool on an FE bin made for a wheel");
  Require(inner_radius_m >= 0 && outer_radius_m > inner_radius_m, "tool.outer_radius_m",
          "must exceed the inner radius, which must not be negative");
  ToolNodes tool;
  double area_m2 = 0, area_moment_m3 = 0;
  for (size_t k = 0; k < surface_.size(); ++k) {
    const Vec3& x = solver_->mesh().reference_positions_m[surface_[k]];
    const double r = std::hypot(x.x(), x.y());
    if (r >= inner_radius_m - 1e-9 && r <= outer_radius_m + 1e-9) {
      tool.nodes.push_back(surface_[k]);
      tool.areas_m2.push_back(areas_m2_[k]);
      area_m2 += areas_m2_[k];
      area_moment_m3 += areas_m2_[k] * r;
    }
  }
  Require(!tool.nodes.empty(), "tool.outer_radius_m", "covers no surface node: refine the bin");
  tools_.push_back(std::move(tool));
  return {static_cast<int>(tools_.size()) - 1, area_m2 * whole_per_modelled_,
          area_moment_m3 * whole_per_modelled_};
}

void FeSoilBin::DriveFlatTool(int tool_id, const FlatToolDrive& drive) {
  Tool(tool_id);
  ToolNodes& tool = tools_[tool_id];
  fe::ExplicitSolver& s = *solver_;
  auto& f_ext = s.external_forces_n();
  tool.speed_before_m_s = tool.drive.vertical == FlatToolDrive::Vertical::kSpeed && tool.pushes
                              ? tool.drive.vertical_speed_m_s
                              : 0.0;
  for (size_t i = 0; i < tool.nodes.size(); ++i) {
    const int n = tool.nodes[i];
    // Vertical: a smooth plate prescribes the nodes' speed; a pressure loads their areas.
    if (drive.vertical == FlatToolDrive::Vertical::kSpeed) {
      s.PrescribeVelocity(n, 2, -drive.vertical_speed_m_s);
    } else {
      if (tool.pushes) s.Release(n, 2);
      f_ext[n] = Vec3(0, 0, -drive.normal_pressure_pa * tool.areas_m2[i] * drive.load_fraction);
    }
    // In plane: the gripped soil moves with the tool, a rigid turn about z.
    if (drive.in_plane == FlatToolDrive::InPlane::kHeld) {
      s.PrescribeVelocity(n, 0);
      s.PrescribeVelocity(n, 1);
    } else if (drive.in_plane == FlatToolDrive::InPlane::kTurning) {
      const Vec3& x = s.positions_m()[n];
      s.PrescribeVelocity(n, 0, -drive.angular_speed_rad_s * x.y());
      s.PrescribeVelocity(n, 1, drive.angular_speed_rad_s * x.x());
    } else if (tool.grips) {
      s.Release(n, 0);
      s.Release(n, 1);
    }
  }
  tool.pushes = drive.vertical == FlatToolDrive::Vertical::kSpeed;
  tool.grips = drive.in_plane != FlatToolDrive::InPlane::kFree;
  tool.drive = drive;
}

FlatToolLoad FeSoilBin::FlatToolReaction(int tool_id) const {
  const ToolNodes& tool = Tool(tool_id);
  const fe::ExplicitSolver& s = *solver_;
  FlatToolLoad load;
  if (tool.pushes) {
    // The force on the prescribed nodes balances their inertia, weight and internal force:
    // F_z = m a - m g + f_int (no other external force acts there), a = -(dv / dt).
    const double speed = tool.drive.vertical_speed_m_s;
    // fe::ExplicitOptions' default, which the bins keep.
    const double gravity_m_s2 = units::kStandardGravityMps2;
    double force_z = 0;
    for (int n : tool.nodes) {
      const double m = s.nodal_masses_kg()[n];
      // Inertia of the (scaled) mass, weight of the physical one.
      force_z += m * (-(speed - tool.speed_before_m_s) / last_dt_s_) +
                 m / s.mass_scaling() * gravity_m_s2 +
                 s.internal_forces_n()[n].z();
    }
    load.normal_force_n = -force_z * whole_per_modelled_;
  } else {
    double area_m2 = 0;
    for (double a : tool.areas_m2) area_m2 += a;
    load.normal_force_n =
        tool.drive.normal_pressure_pa * tool.drive.load_fraction * area_m2 * whole_per_modelled_;
  }
  // Torque about z the tool applies, quasi-statically the internal forces of its nodes.
  double torque = 0;
  for (int n : tool.nodes) {
    const Vec3& x = s.positions_m()[n];
    const Vec3& f = s.internal_forces_n()[n];
    torque += x.x() * f.y() - x.y() * f.x();
  }
  load.torque_nm = torque * whole_per_modelled_;
  return load;
}

double WaveSpeedMS(const material::ConstitutiveModel& model, double density_kg_m3) {
  const material::ElasticModuli moduli = model.InitialElasticModuli();
  return std::sqrt((moduli.bulk_pa + 4.0 / 3.0 * moduli.shear_pa) / density_kg_m3);
}

fe::ExplicitOptions SolverOptions(const FeBinSoil& soil, const FeBinOptions& options,
                                  double damping_per_s) {
  fe::ExplicitOptions fe_options;
  fe_options.density_kg_m3 = soil.density_kg_m3;
  fe_options.hourglass_coefficient = options.hourglass_coefficient;
  fe_options.hourglass_viscosity = options.hourglass_viscosity;
  fe_options.time_step_safety = options.time_step_safety;
  fe_options.mass_damping_per_s = damping_per_s;
  fe_options.threads = options.threads;
  return fe_options;
}

// The soil's initial point states by depth (FeBinSoil::initial_state_at_depth), one call per
// distinct depth of an element centre below z = 0.
void SetInitialStatesByDepth(const FeBinSoil& soil, fe::ExplicitSolver& solver) {
  if (!soil.initial_state_at_depth) return;
  const fe::HexMesh& mesh = solver.mesh();
  std::map<double, std::string> states;  // by depth, m
  for (int e = 0; e < mesh.num_elements(); ++e) {
    double centre_z_m = 0;
    for (int node : mesh.elements[e]) centre_z_m += mesh.reference_positions_m[node].z() / 8.0;
    const double depth_m = std::max(0.0, -centre_z_m);
    auto found = states.find(depth_m);
    if (found == states.end()) {
      found = states.emplace(depth_m, soil.initial_state_at_depth(depth_m)).first;
    }
    solver.SetInitialPointState(e, found->second);
  }
}

// Lines from -extent (or 0) to +extent, fine within `fine_extent` of the centre.
std::vector<double> CentredLines(double extent_m, double fine_extent_m, double h, bool mirrored) {
  std::vector<double> half = fe::GradedLines(0, extent_m, h, fine_extent_m, 1.3, 4 * h);
  return mirrored ? fe::MirroredLines(half) : half;
}

}  // namespace

void FeBinSoil::Validate(const std::string& p) const {
  Require(model != nullptr, p + "model", "is missing");
  Require(density_kg_m3 > 0 && std::isfinite(density_kg_m3), p + "density_kg_m3",
          "must be positive");
  Require(wheel_friction_coefficient >= 0 && std::isfinite(wheel_friction_coefficient),
          p + "wheel_friction_coefficient", "must not be negative");
  Require(wheel_adhesion_pa >= 0 && std::isfinite(wheel_adhesion_pa), p + "wheel_adhesion_pa",
          "must not be negative");
}

FeBinSoil MakeFeBinSoil(const material::MaterialRegistry& registry, const FeBinSoilSpec& spec) {
  FeBinSoil soil;
  soil.label = spec.label;
  soil.model = registry.Make(spec.model_name, spec.parameters);
  soil.density_kg_m3 = spec.density_kg_m3;
  soil.wheel_friction_coefficient = spec.wheel_friction_coefficient;
  soil.wheel_adhesion_pa = spec.wheel_adhesion_pa;
  soil.Validate("soil.");
  return soil;
}

FeBinSoil FeBinSoilFromFeSoil(const FeSoil& soil) {
  FeBinSoil bin_soil;
  bin_soil.label = soil.name;
  bin_soil.model = std::make_shared<material::DruckerPrager>(soil.strength);
  bin_soil.density_kg_m3 = soil.density_kg_m3;
  bin_soil.wheel_friction_coefficient =
      std::tan(units::DegreesToRadians(soil.strength.friction_angle_deg));
  bin_soil.wheel_adhesion_pa = soil.strength.cohesion_pa;
  return bin_soil;
}

FeSoilBinFactory::FeSoilBinFactory(FeBinSoil soil, FeBinOptions options)
    : soil_(std::move(soil)), options_(options) {
  soil_.Validate("soil.");
}

std::string FeSoilBinFactory::Describe() const {
  return "fe " + soil_.model->Name() + (soil_.label.empty() ? "" : " (" + soil_.label + ")");
}

std::unique_ptr<SoilBin> FeSoilBinFactory::MakeWheelBin(const WheelBinLayout& layout) const {
  Require(layout.wheel_radius_m > 0 && layout.wheel_width_m > 0, "bin.wheel_radius_m",
          "the wheel's radius and width must be positive");
  const double h = layout.resolution_m;
  fe::SoilBinSpec bin;
  bin.length_m = layout.length_m;
  bin.width_m = layout.width_m;
  bin.depth_m = layout.depth_m;
  bin.element_size_m = h;
  bin.path_half_width_m = layout.path_half_width_m;
  bin.fine_depth_m = layout.fine_depth_m;
  bin.half_symmetric = true;
  fe::HexMesh mesh = fe::MeshSoilBin(bin);

  const material::ElasticModuli moduli = soil_.model->InitialElasticModuli();
  const double p_wave_modulus_pa = moduli.bulk_pa + 4.0 / 3.0 * moduli.shear_pa;
  const double wave_speed_m_s = std::sqrt(p_wave_modulus_pa / soil_.density_kg_m3);
  // Settling damps the bin's first vertical mode critically: omega_1 = pi c / (2 depth).
  const double settle_damping_per_s = 2 * kPi * wave_speed_m_s / (2 * bin.depth_m);
  auto solver = std::make_unique<fe::ExplicitSolver>(
      std::move(mesh), soil_.model, SolverOptions(soil_, options_, settle_damping_per_s));
  fe::ExplicitSolver& s = *solver;
  SetInitialStatesByDepth(soil_, s);
  const fe::HexMesh& m = s.mesh();
  // Floor fixed; end walls and the far side wall on rollers; y = 0 is the symmetry plane.
  for (int n : m.NodesOnPlane(2, -bin.depth_m)) {
    for (int d = 0; d < 3; ++d) s.PrescribeVelocity(n, d);
  }
  for (int n : m.NodesOnPlane(0, 0)) s.PrescribeVelocity(n, 0);
  for (int n : m.NodesOnPlane(0, bin.length_m)) s.PrescribeVelocity(n, 0);
  for (int n : m.NodesOnPlane(1, 0)) s.PrescribeVelocity(n, 1);
  for (int n : m.NodesOnPlane(1, 0.5 * bin.width_m)) s.PrescribeVelocity(n, 1);

  auto result = std::make_unique<FeSoilBin>(std::move(solver), settle_damping_per_s, 0.0,
                                            /*modelled_fraction=*/0.5, /*tools_allowed=*/false);
  // Penalty stiffness of the order of the soil's own nodal stiffness, (K + 4G/3) h: sinkage error
  // p h / (K + 4G/3) stays far below the element size, and the node's frequency at most doubles.
  WheelContactParams contact;
  contact.radius_m = layout.wheel_radius_m;
  contact.width_m = layout.wheel_width_m;
  contact.friction_coefficient = soil_.wheel_friction_coefficient;
  contact.adhesion_pa = soil_.wheel_adhesion_pa;
  contact.normal_stiffness_n_m = p_wave_modulus_pa * h;
  contact.tangential_stiffness_n_m = contact.normal_stiffness_n_m;
  double lightest_surface_node_kg = std::numeric_limits<double>::infinity();
  for (int n : result->surface()) {
    lightest_surface_node_kg = std::min(lightest_surface_node_kg, s.nodal_masses_kg()[n]);
  }
  const double contact_step_s =
      options_.time_step_safety * 2 *
      std::sqrt(lightest_surface_node_kg /
                (contact.normal_stiffness_n_m + contact.tangential_stiffness_n_m +
                 p_wave_modulus_pa * h));
  result->set_stable_time_step_s(std::min(s.StableTimeStep(), contact_step_s));
  result->set_wheel(
      std::make_unique<WheelContact>(contact, result->surface(), result->surface_areas_m2()));
  result->ScaleMassToTimeStep(options_.target_time_step_s);
  return result;
}

std::unique_ptr<SoilBin> FeSoilBinFactory::MakeToolBin(const ToolBinLayout& layout) const {
  const double h = layout.resolution_m;
  const bool whole = layout.turning_tool;
  const double extent_m = layout.half_extent_m;
  std::vector<double> z_lines = fe::DepthLines(layout.depth_m, h, layout.fine_extent_m, 1.3, 4 * h);
  fe::HexMesh mesh = fe::MeshBox(CentredLines(extent_m, layout.fine_extent_m, h, whole),
                                 CentredLines(extent_m, layout.fine_extent_m, h, whole), z_lines);
  // Quasi-static tests: the box's first vertical mode, omega_1 = pi c / (2 depth), damped
  // critically.
  const double settle_damping_per_s =
      kPi * WaveSpeedMS(*soil_.model, soil_.density_kg_m3) / layout.depth_m;
  auto solver = std::make_unique<fe::ExplicitSolver>(
      std::move(mesh), soil_.model, SolverOptions(soil_, options_, settle_damping_per_s));
  fe::ExplicitSolver& s = *solver;
  SetInitialStatesByDepth(soil_, s);
  const fe::HexMesh& m = s.mesh();
  // Floor fixed, side walls and symmetry planes on rollers.
  for (int n : m.NodesOnPlane(2, -layout.depth_m)) {
    for (int d = 0; d < 3; ++d) s.PrescribeVelocity(n, d);
  }
  for (int axis = 0; axis < 2; ++axis) {
    for (int n : m.NodesOnPlane(axis, extent_m)) s.PrescribeVelocity(n, axis);
    for (int n : m.NodesOnPlane(axis, whole ? -extent_m : 0.0)) s.PrescribeVelocity(n, axis);
  }
  const double dt = s.StableTimeStep();
  auto result = std::make_unique<FeSoilBin>(std::move(solver), settle_damping_per_s, dt,
                                            /*modelled_fraction=*/whole ? 1.0 : 0.25,
                                            /*tools_allowed=*/true);
  result->ScaleMassToTimeStep(options_.target_time_step_s);
  return result;
}

}  // namespace gonogo::rig
