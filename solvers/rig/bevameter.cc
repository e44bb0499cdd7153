#include "solvers/rig/bevameter.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"

namespace gonogo::rig {
namespace {

using units::kPi;

double Smooth(double fraction) {
  fraction = std::clamp(fraction, 0.0, 1.0);
  return 0.5 - 0.5 * std::cos(kPi * fraction);
}

double StepOrThrow(SoilBin& bin, double dt, const RigOptions& options, int step,
                   const char* test) {
  const BinStepStatus status = bin.Step(dt);
  if (!status.ok) {
    throw std::runtime_error(std::string("virtual bevameter (") + test + "): " + status.reason);
  }
  if (step % options.poll_every_steps == 0 && options.cancelled && options.cancelled()) throw CancelledError();
  return bin.time_s();
}

void Settle(SoilBin& bin, double seconds, double dt, const RigOptions& options) {
  const int steps = static_cast<int>(std::ceil(seconds / dt));
  for (int k = 0; k < steps; ++k) StepOrThrow(bin, dt, options, k, "settling");
}

// A smooth rigid plate pushed into the soil at constant speed (after a smooth start).
PlateTest RunPlate(const SoilBinFactory& soil_bin, double radius_m, const BevameterSpec& spec,
                   double h, const RigOptions& options) {
  ToolBinLayout layout;
  layout.half_extent_m = 3 * spec.large_plate_radius_m;
  layout.fine_extent_m = 1.3 * spec.large_plate_radius_m;
  layout.depth_m = layout.half_extent_m;
  layout.resolution_m = h;
  layout.turning_tool = false;
  const std::unique_ptr<SoilBin> bin = soil_bin.MakeToolBin(layout);
  SoilBin& s = *bin;
  const double dt = s.StableTimeStepS();
  Settle(s, 0.05, dt, options);
  const FlatTool plate = s.AttachFlatTool(0, radius_m);
  PlateTest test;
  test.radius_m = std::sqrt(plate.area_m2 / kPi);
  const double ramp_s = spec.start_ramp_s;
  const double duration = spec.plate_sinkage_m / spec.plate_speed_m_s + 0.5 * ramp_s;
  const int steps = static_cast<int>(std::ceil(duration / dt));
  const double start = s.time_s();
  double sinkage = 0;
  FlatToolDrive drive;
  drive.vertical = FlatToolDrive::Vertical::kSpeed;
  drive.in_plane = FlatToolDrive::InPlane::kFree;
  for (int k = 0; k < steps; ++k) {
    const double speed = spec.plate_speed_m_s * Smooth((s.time_s() - start) / ramp_s);
    drive.vertical_speed_m_s = speed;
    s.DriveFlatTool(plate.id, drive);
    StepOrThrow(s, dt, options, k, "plate");
    sinkage += speed * dt;
    if (k % 20 == 0 || k + 1 == steps) {
      test.sinkage_m.push_back(sinkage);
      test.pressure_pa.push_back(s.FlatToolReaction(plate.id).normal_force_n / plate.area_m2);
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

// A grousered ring pressed with a normal pressure, then turned about its axis.
RingTest RunRing(const SoilBinFactory& soil_bin, double normal_pressure_pa,
                 const BevameterSpec& spec, double h, const RigOptions& options) {
  ToolBinLayout layout;
  layout.half_extent_m = 2.5 * spec.ring_outer_radius_m;
  layout.fine_extent_m = 1.2 * spec.ring_outer_radius_m;
  layout.depth_m = spec.ring_outer_radius_m;
  layout.resolution_m = h;
  layout.turning_tool = true;
  const std::unique_ptr<SoilBin> bin = soil_bin.MakeToolBin(layout);
  SoilBin& s = *bin;
  const double dt = s.StableTimeStepS();
  Settle(s, 0.05, dt, options);
  const FlatTool ring = s.AttachFlatTool(spec.ring_inner_radius_m, spec.ring_outer_radius_m);
  const double mean_radius = ring.area_moment_m3 / ring.area_m2;
  // Normal load: the pressure brought on over 0.05 s, while the ring holds the soil against
  // rotation.
  FlatToolDrive drive;
  drive.vertical = FlatToolDrive::Vertical::kPressure;
  drive.normal_pressure_pa = normal_pressure_pa;
  drive.in_plane = FlatToolDrive::InPlane::kHeld;
  const double load_s = 0.05;
  const int load_steps = static_cast<int>(std::ceil(load_s / dt));
  for (int k = 0; k < load_steps; ++k) {
    drive.load_fraction = Smooth((k + 1.0) / load_steps);
    s.DriveFlatTool(ring.id, drive);
    StepOrThrow(s, dt, options, k, "shear ring loading");
  }
  s.SetDampingPerS(spec.ring_damping_fraction * s.SettlingDampingPerS());
  RingTest test;
  test.normal_pressure_pa = normal_pressure_pa;
  const double ramp_s = spec.start_ramp_s;
  const double angular_speed = spec.ring_speed_m_s / mean_radius;
  const double duration = spec.ring_shear_displacement_m / spec.ring_speed_m_s + 0.5 * ramp_s;
  const int steps = static_cast<int>(std::ceil(duration / dt));
  const double start = s.time_s();
  double angle = 0;
  drive.in_plane = FlatToolDrive::InPlane::kTurning;
  for (int k = 0; k < steps; ++k) {
    const double omega = angular_speed * Smooth((s.time_s() - start) / ramp_s);
    drive.angular_speed_rad_s = omega;
    s.DriveFlatTool(ring.id, drive);
    StepOrThrow(s, dt, options, k, "shear ring");
    angle += omega * dt;
    if (k % 20 == 0 || k + 1 == steps) {
      test.shear_displacement_m.push_back(angle * mean_radius);
      // Uniform tau under the ring: T = tau sum(A r).
      test.shear_stress_pa.push_back(s.FlatToolReaction(ring.id).torque_nm / ring.area_moment_m3);
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
  Require(std::isfinite(start_ramp_s) && start_ramp_s > 0, p + "start_ramp_s",
          "must be a positive time, s");
  Require(std::isfinite(ring_damping_fraction) && ring_damping_fraction >= 0 &&
              ring_damping_fraction <= 1,
          p + "ring_damping_fraction", "must lie in [0, 1]");
}

BevameterResult RunVirtualBevameter(const FeSoil& soil, const BevameterSpec& spec,
                                    const RigOptions& options) {
  return RunVirtualBevameter(FeClassicBins(soil, options), spec, options);
}

BevameterResult RunVirtualBevameter(const SoilBinFactory& soil_bin, const BevameterSpec& spec,
                                    const RigOptions& options) {
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
    result.plates.push_back(RunPlate(soil_bin, radius, spec, plate_h, options));
    if (options.progress) options.progress(static_cast<double>(++done) / runs);
  }
  for (double sigma : spec.ring_normal_pressures_pa) {
    result.rings.push_back(RunRing(soil_bin, sigma, spec, ring_h, options));
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
  *friction_angle_deg = units::RadiansToDegrees(std::atan(slope));
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
