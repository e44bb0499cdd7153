#include "solvers/rig/bevameter.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "solvers/common/errors.h"
#include "solvers/fe/explicit_solver.h"
#include "solvers/fe/mesh.h"
#include "solvers/material/drucker_prager.h"
#include "solvers/rig/wheel_contact.h"

namespace gonogo::rig {
namespace {

using fe::Vec3;

constexpr double kPi = 3.14159265358979323846;
constexpr double kGravity = 9.81;

double Smooth(double fraction) {
  fraction = std::clamp(fraction, 0.0, 1.0);
  return 0.5 - 0.5 * std::cos(kPi * fraction);
}

// Lines from -extent (or 0) to +extent, fine within `fine_extent` of the centre.
std::vector<double> CentredLines(double extent_m, double fine_extent_m, double h, bool mirrored) {
  std::vector<double> half = fe::GradedLines(0, extent_m, h, fine_extent_m, 1.3, 4 * h);
  return mirrored ? fe::MirroredLines(half) : half;
}

struct Bin {
  std::unique_ptr<fe::ExplicitSolver> solver;
  std::vector<int> surface;
  std::vector<double> areas;
  double settle_damping_per_s = 0;
};

// A soil box with the top at z = 0: quarter-symmetric (x, y >= 0) for the plates, whole for the
// ring. Floor fixed, side walls on rollers, symmetry planes on rollers.
Bin MakeBin(const FeSoil& soil, double extent_m, double fine_extent_m, double depth_m, double h,
            bool whole, const RigOptions& options) {
  std::vector<double> z_lines = fe::DepthLines(depth_m, h, fine_extent_m, 1.3, 4 * h);
  fe::HexMesh mesh = fe::MeshBox(CentredLines(extent_m, fine_extent_m, h, whole),
                                 CentredLines(extent_m, fine_extent_m, h, whole), z_lines);
  auto model = std::make_shared<material::DruckerPrager>(soil.strength);
  const material::ElasticModuli moduli = model->InitialElasticModuli();
  const double wave_speed_m_s =
      std::sqrt((moduli.bulk_pa + 4.0 / 3.0 * moduli.shear_pa) / soil.density_kg_m3);
  fe::ExplicitOptions fe_options;
  fe_options.density_kg_m3 = soil.density_kg_m3;
  fe_options.hourglass_coefficient = options.hourglass_coefficient;
  fe_options.hourglass_viscosity = options.hourglass_viscosity;
  fe_options.time_step_safety = options.time_step_safety;
  fe_options.threads = options.threads;
  Bin bin;
  // Quasi-static tests: the box's first vertical mode, omega_1 = pi c / (2 depth), damped
  // critically.
  bin.settle_damping_per_s = kPi * wave_speed_m_s / depth_m;
  fe_options.mass_damping_per_s = bin.settle_damping_per_s;
  bin.solver = std::make_unique<fe::ExplicitSolver>(std::move(mesh), model, fe_options);
  fe::ExplicitSolver& s = *bin.solver;
  const fe::HexMesh& m = s.mesh();
  for (int n : m.NodesOnPlane(2, -depth_m)) {
    for (int d = 0; d < 3; ++d) s.PrescribeVelocity(n, d);
  }
  for (int axis = 0; axis < 2; ++axis) {
    for (int n : m.NodesOnPlane(axis, extent_m)) s.PrescribeVelocity(n, axis);
    for (int n : m.NodesOnPlane(axis, whole ? -extent_m : 0.0)) s.PrescribeVelocity(n, axis);
  }
  TopSurfaceNodes(m, &bin.surface, &bin.areas);
  return bin;
}

double StepOrThrow(fe::ExplicitSolver& solver, double dt, const RigOptions& options, int step,
                   const char* test) {
  const fe::StepStatus status = solver.Step(dt);
  if (!status.ok) {
    throw std::runtime_error(std::string("virtual bevameter (") + test + "): " + status.reason);
  }
  if (step % 200 == 0 && options.cancelled && options.cancelled()) throw CancelledError();
  return solver.time_s();
}

void Settle(fe::ExplicitSolver& solver, double seconds, double dt, const RigOptions& options) {
  const int steps = static_cast<int>(std::ceil(seconds / dt));
  for (int k = 0; k < steps; ++k) StepOrThrow(solver, dt, options, k, "settling");
}

PlateTest RunPlate(const FeSoil& soil, double radius_m, const BevameterSpec& spec, double h,
                   const RigOptions& options) {
  const double extent = 3 * spec.large_plate_radius_m;
  Bin bin = MakeBin(soil, extent, 1.3 * spec.large_plate_radius_m, extent, h, false, options);
  fe::ExplicitSolver& s = *bin.solver;
  const double dt = s.StableTimeStep();
  Settle(s, 0.05, dt, options);
  // The plate: surface nodes within its radius move down together (smooth rigid plate).
  std::vector<int> plate;
  double quarter_area = 0;
  for (size_t k = 0; k < bin.surface.size(); ++k) {
    const Vec3& x = s.mesh().reference_positions_m[bin.surface[k]];
    if (std::hypot(x.x(), x.y()) <= radius_m + 1e-9) {
      plate.push_back(bin.surface[k]);
      quarter_area += bin.areas[k];
    }
  }
  PlateTest test;
  test.radius_m = std::sqrt(4 * quarter_area / kPi);
  const double ramp_s = 0.02;
  const double duration = spec.plate_sinkage_m / spec.plate_speed_m_s + 0.5 * ramp_s;
  const int steps = static_cast<int>(std::ceil(duration / dt));
  const double start = s.time_s();
  double sinkage = 0, previous_speed = 0;
  for (int k = 0; k < steps; ++k) {
    const double speed = spec.plate_speed_m_s * Smooth((s.time_s() - start) / ramp_s);
    for (int n : plate) s.PrescribeVelocity(n, 2, -speed);
    StepOrThrow(s, dt, options, k, "plate");
    sinkage += speed * dt;
    // Force the plate exerts on its nodes: m a - m g + f_int (no other external force there).
    double force_z = 0;
    for (int n : plate) {
      const double m = s.nodal_masses_kg()[n];
      force_z += m * (-(speed - previous_speed) / dt) + m * kGravity + s.internal_forces_n()[n].z();
    }
    previous_speed = speed;
    if (k % 20 == 0 || k + 1 == steps) {
      test.sinkage_m.push_back(sinkage);
      test.pressure_pa.push_back(-force_z / quarter_area);
    }
  }
  // Fit over the sinkages past a tenth of the push (the start is the elastic response).
  std::vector<double> z, p;
  for (size_t k = 0; k < test.sinkage_m.size(); ++k) {
    if (test.sinkage_m[k] >= 0.1 * spec.plate_sinkage_m && test.pressure_pa[k] > 0) {
      z.push_back(test.sinkage_m[k]);
      p.push_back(test.pressure_pa[k]);
    }
  }
  const PowerLaw fit = FitPowerLaw(z, p);
  test.k = fit.k;
  test.n = fit.n;
  return test;
}

RingTest RunRing(const FeSoil& soil, double normal_pressure_pa, const BevameterSpec& spec,
                 double h, const RigOptions& options) {
  const double extent = 2.5 * spec.ring_outer_radius_m;
  Bin bin = MakeBin(soil, extent, 1.2 * spec.ring_outer_radius_m, spec.ring_outer_radius_m, h,
                    true, options);
  fe::ExplicitSolver& s = *bin.solver;
  const double dt = s.StableTimeStep();
  Settle(s, 0.05, dt, options);
  std::vector<int> ring;
  std::vector<double> ring_areas;
  double area_radius = 0, area = 0;
  for (size_t k = 0; k < bin.surface.size(); ++k) {
    const Vec3& x = s.mesh().reference_positions_m[bin.surface[k]];
    const double r = std::hypot(x.x(), x.y());
    if (r >= spec.ring_inner_radius_m - 1e-9 && r <= spec.ring_outer_radius_m + 1e-9) {
      ring.push_back(bin.surface[k]);
      ring_areas.push_back(bin.areas[k]);
      area += bin.areas[k];
      area_radius += bin.areas[k] * r;
    }
  }
  const double mean_radius = area_radius / area;
  // Normal load: the pressure on every ring node's area, brought on over 0.05 s, while the ring
  // holds the nodes against rotation.
  auto& f_ext = s.external_forces_n();
  const double load_s = 0.05;
  const int load_steps = static_cast<int>(std::ceil(load_s / dt));
  for (int k = 0; k < load_steps; ++k) {
    for (size_t i = 0; i < ring.size(); ++i) {
      f_ext[ring[i]] =
          Vec3(0, 0, -normal_pressure_pa * ring_areas[i] * Smooth((k + 1.0) / load_steps));
      s.PrescribeVelocity(ring[i], 0);
      s.PrescribeVelocity(ring[i], 1);
    }
    StepOrThrow(s, dt, options, k, "shear ring loading");
  }
  s.set_mass_damping_per_s(0.2 * bin.settle_damping_per_s);
  RingTest test;
  test.normal_pressure_pa = normal_pressure_pa;
  const double ramp_s = 0.02;
  const double angular_speed = spec.ring_speed_m_s / mean_radius;
  const double duration = spec.ring_shear_displacement_m / spec.ring_speed_m_s + 0.5 * ramp_s;
  const int steps = static_cast<int>(std::ceil(duration / dt));
  const double start = s.time_s();
  double angle = 0;
  for (int k = 0; k < steps; ++k) {
    const double omega = angular_speed * Smooth((s.time_s() - start) / ramp_s);
    for (int n : ring) {
      const Vec3& x = s.positions_m()[n];
      s.PrescribeVelocity(n, 0, -omega * x.y());
      s.PrescribeVelocity(n, 1, omega * x.x());
    }
    StepOrThrow(s, dt, options, k, "shear ring");
    angle += omega * dt;
    // Torque the ring applies about z: sum of x F_y - y F_x with F = f_int (quasi-static).
    double torque = 0;
    for (int n : ring) {
      const Vec3& x = s.positions_m()[n];
      const Vec3& f = s.internal_forces_n()[n];
      torque += x.x() * f.y() - x.y() * f.x();
    }
    if (k % 20 == 0 || k + 1 == steps) {
      test.shear_displacement_m.push_back(angle * mean_radius);
      test.shear_stress_pa.push_back(torque / area_radius);  // uniform tau: T = tau sum(A r)
    }
  }
  test.max_shear_stress_pa =
      *std::max_element(test.shear_stress_pa.begin(), test.shear_stress_pa.end());
  return test;
}

}  // namespace

void BevameterSpec::Validate(const std::string& p) const {
  Require(small_plate_radius_m > 0, p + "small_plate_radius_m", "must be positive");
  Require(large_plate_radius_m > small_plate_radius_m, p + "large_plate_radius_m",
          "must exceed the small plate's");
  Require(plate_sinkage_m > 0, p + "plate_sinkage_m", "must be positive");
  Require(plate_speed_m_s > 0, p + "plate_speed_m_s", "must be positive");
  Require(ring_inner_radius_m > 0, p + "ring_inner_radius_m", "must be positive");
  Require(ring_outer_radius_m > ring_inner_radius_m, p + "ring_outer_radius_m",
          "must exceed the inner radius");
  Require(ring_normal_pressures_pa.size() >= 2, p + "ring_normal_pressures_pa",
          "needs at least two pressures");
  for (double s : ring_normal_pressures_pa) {
    Require(s > 0, p + "ring_normal_pressures_pa", "must be positive");
  }
  Require(ring_shear_displacement_m > 0, p + "ring_shear_displacement_m", "must be positive");
  Require(ring_speed_m_s > 0, p + "ring_speed_m_s", "must be positive");
}

BevameterResult RunVirtualBevameter(const FeSoil& soil, const BevameterSpec& spec,
                                    const RigOptions& options) {
  soil.Validate("soil.");
  spec.Validate("bevameter.");
  options.Validate("rig.");
  const double plate_h =
      options.element_size_m > 0 ? options.element_size_m : spec.small_plate_radius_m / 4;
  const double ring_h = options.element_size_m > 0
                            ? options.element_size_m
                            : (spec.ring_outer_radius_m - spec.ring_inner_radius_m) / 4;
  BevameterResult result;
  const int runs = 2 + static_cast<int>(spec.ring_normal_pressures_pa.size());
  int done = 0;
  for (double radius : {spec.small_plate_radius_m, spec.large_plate_radius_m}) {
    result.plates.push_back(RunPlate(soil, radius, spec, plate_h, options));
    if (options.progress) options.progress(static_cast<double>(++done) / runs);
  }
  for (double sigma : spec.ring_normal_pressures_pa) {
    result.rings.push_back(RunRing(soil, sigma, spec, ring_h, options));
    if (options.progress) options.progress(static_cast<double>(++done) / runs);
  }
  BekkerParameters& b = result.fitted;
  b.n = 0.5 * (result.plates[0].n + result.plates[1].n);
  FitBekkerModuli(result.plates[0].radius_m, result.plates[0].k, result.plates[1].radius_m,
                  result.plates[1].k, &b.kc, &b.kphi);
  std::vector<double> sigma, tau_max;
  for (const RingTest& r : result.rings) {
    sigma.push_back(r.normal_pressure_pa);
    tau_max.push_back(r.max_shear_stress_pa);
  }
  FitMohrCoulomb(sigma, tau_max, &b.cohesion_pa, &b.friction_angle_deg);
  double k_sum = 0;
  for (const RingTest& r : result.rings) {
    k_sum += FitShearDeformationModulus(r.shear_displacement_m, r.shear_stress_pa,
                                        r.max_shear_stress_pa);
  }
  b.shear_deformation_m = k_sum / result.rings.size();
  return result;
}

PowerLaw FitPowerLaw(const std::vector<double>& x, const std::vector<double>& y) {
  Require(x.size() == y.size(), "fit", "x and y differ in length");
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int count = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    if (!(x[i] > 0 && y[i] > 0)) continue;
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
    ++count;
  }
  Require(count >= 2, "fit", "needs at least two positive points");
  const double denominator = count * sxx - sx * sx;
  Require(denominator > 0, "fit", "needs two distinct x values");
  PowerLaw fit;
  fit.n = (count * sxy - sx * sy) / denominator;
  fit.k = std::exp((sy - fit.n * sx) / count);
  return fit;
}

void FitBekkerModuli(double radius1_m, double k1, double radius2_m, double k2, double* kc,
                     double* kphi) {
  Require(radius1_m > 0 && radius2_m > 0 && radius1_m != radius2_m, "fit",
          "needs two different plate radii");
  *kc = (k1 - k2) / (1 / radius1_m - 1 / radius2_m);
  *kphi = k1 - *kc / radius1_m;
}

void FitMohrCoulomb(const std::vector<double>& normal_pa, const std::vector<double>& max_shear_pa,
                    double* cohesion_pa, double* friction_angle_deg) {
  Require(normal_pa.size() == max_shear_pa.size() && normal_pa.size() >= 2, "fit",
          "needs at least two (sigma, tau_max) pairs");
  const double n = static_cast<double>(normal_pa.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < normal_pa.size(); ++i) {
    sx += normal_pa[i];
    sy += max_shear_pa[i];
    sxx += normal_pa[i] * normal_pa[i];
    sxy += normal_pa[i] * max_shear_pa[i];
  }
  const double denominator = n * sxx - sx * sx;
  Require(denominator > 0, "fit", "needs two distinct normal pressures");
  const double slope = (n * sxy - sx * sy) / denominator;
  *cohesion_pa = (sy - slope * sx) / n;
  *friction_angle_deg = std::atan(slope) * 180 / kPi;
}

double FitShearDeformationModulus(const std::vector<double>& j_m,
                                  const std::vector<double>& tau_pa, double max_tau_pa) {
  Require(j_m.size() == tau_pa.size() && max_tau_pa > 0, "fit", "bad shear curve");
  double sjj = 0, sjl = 0;
  for (size_t i = 0; i < j_m.size(); ++i) {
    const double ratio = tau_pa[i] / max_tau_pa;
    if (ratio <= 0.05 || ratio >= 0.95 || j_m[i] <= 0) continue;
    sjj += j_m[i] * j_m[i];
    sjl += j_m[i] * std::log(1 - ratio);
  }
  Require(sjl < 0, "fit", "the shear curve has no points between 5 % and 95 % of its maximum");
  return -sjj / sjl;
}

void PrintBevameter(const BevameterResult& result, std::FILE* out) {
  std::fprintf(out, "# plate pressure-sinkage: radius_m,sinkage_m,pressure_pa\n");
  for (const PlateTest& p : result.plates) {
    for (size_t k = 0; k < p.sinkage_m.size(); ++k) {
      std::fprintf(out, "plate,%.4f,%.5f,%.1f\n", p.radius_m, p.sinkage_m[k], p.pressure_pa[k]);
    }
  }
  std::fprintf(out, "# shear ring: normal_pa,shear_displacement_m,shear_stress_pa\n");
  for (const RingTest& r : result.rings) {
    for (size_t k = 0; k < r.shear_displacement_m.size(); ++k) {
      std::fprintf(out, "ring,%.0f,%.5f,%.1f\n", r.normal_pressure_pa, r.shear_displacement_m[k],
                   r.shear_stress_pa[k]);
    }
  }
  for (const PlateTest& p : result.plates) {
    std::fprintf(out, "# plate radius %.4f m: p = %.4g z^%.3f\n", p.radius_m, p.k, p.n);
  }
  for (const RingTest& r : result.rings) {
    std::fprintf(out, "# ring at %.0f Pa: tau_max %.1f Pa\n", r.normal_pressure_pa,
                 r.max_shear_stress_pa);
  }
  const BekkerParameters& b = result.fitted;
  std::fprintf(out,
               "# fitted: n=%.3f,kc=%.4g,kphi=%.4g,c=%.1f,phi_deg=%.2f,K=%.4f "
               "(SI: kc N/m^(n+1), kphi N/m^(n+2), c Pa, K m)\n",
               b.n, b.kc, b.kphi, b.cohesion_pa, b.friction_angle_deg, b.shear_deformation_m);
}

}  // namespace gonogo::rig
