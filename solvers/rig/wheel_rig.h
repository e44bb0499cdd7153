// The single-wheel test rig over any soil bin (soil_bin.h): the drawbar-pull procedure of seed 001
// section 6.3, a constant-slip and a towed mode, all giving a TractionCurve. The entry points that
// take an FeSoil build the fe-classic bin (Drucker-Prager, fe_soil_bin.h) and run the same code.
//
// Procedure (seed 001, section 6.3; figures for its full-scale tyre):
//   1. gravity settle: the soil bin comes to rest under its own weight (heavily damped);
//   2. load settle: the wheel's normal load W is applied at the hub and the wheel sinks to rest;
//   3. self-propelled: angular speed omega (5.47 rad/s, 52.26 rpm) and forward speed V_0 = omega R
//      (2.76 m/s for the seed's 0.505 m rolling radius), slip 0, for 0.5 s (brought up smoothly
//      over the first 0.1 s);
//   4. slip ramp: omega held, V falls linearly to 0 over 2 s, so slip s = 1 - V / (omega R) runs
//      from 0 to 1.
// The seed gives omega and V_0 for its full-scale tyre only; the rig keeps omega for every wheel,
// so the distance run, 1.5 omega R, and with it the soil bin, scale with the wheel.
// The wheel is rigid (radius R = d / 2 of the tyre), moves on prescribed forward and angular speed,
// and is free vertically under W. The bin reports whole-wheel forces (the FE bin meshes the half
// y >= 0 and doubles them).
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "solvers/common/tier.h"
#include "solvers/common/traction.h"
#include "solvers/rig/fe_soil_bin.h"
#include "solvers/rig/fe_soils.h"
#include "solvers/rig/soil_bin.h"

namespace gonogo::rig {

struct RigWheel {
  double radius_m = 0;
  double width_m = 0;
  double load_n = 0;  // W
  void Validate(const std::string& field_prefix) const;
};

struct DrawbarPullProcedure {
  double gravity_settle_s = 0.15;
  double load_settle_s = 0.3;
  double self_propelled_s = 0.5;     // seed 001: 0.5 s
  double slip_ramp_s = 2.0;          // seed 001: 2 s
  double speed_ramp_up_s = 0.1;      // inside the self-propelled phase
  double angular_speed_rad_s = 5.47;  // seed 001: 52.26 rpm
  void Validate(const std::string& field_prefix) const;
};

struct RigOptions {
  double element_size_m = 0;  // bin resolution near the wheel path; 0: R / elements_per_radius
  double elements_per_radius = 6;
  double rolling_damping_per_s = 2;  // soil bin damping once the wheel rolls, 1/s
  // FE numerics (FeBinOptions), read only by the entry points that take an FeSoil; a
  // SoilBinFactory carries its own.
  double hourglass_coefficient = 0.05;  // fe::ExplicitOptions
  double hourglass_viscosity = 0.1;     // fe::ExplicitOptions
  double time_step_safety = 0.5;
  int threads = 1;
  // Called now and then with the fraction of simulated time done.
  std::function<void(double fraction)> progress;
  CancelCheck cancelled;  // polled every poll_every_steps; CancelledError once it returns true
  // Steps between cancellation polls and progress reports: cheap steps poll seldom, expensive
  // ones (an RVE per element) often, so a cancel takes effect within seconds.
  int poll_every_steps = 200;
  // Checkpoints, on bins that can (SoilBin::SaveState; the FE wheel bins): with checkpoint_dir
  // set (an existing directory), the run writes its state there at a poll step once
  // checkpoint_every_s of wall time has passed since the last, and a run that finds a checkpoint
  // of the same run there (same bin, step and procedure) resumes from it: its curve is the same,
  // bit for bit, as an uninterrupted run's. A checkpoint of another run is ignored (and replaced).
  std::string checkpoint_dir;
  double checkpoint_every_s = 60;
  // Called after each checkpoint with the FE steps done (tests, logs); may be empty.
  std::function<void(int steps_done)> on_checkpoint;
  void Validate(const std::string& field_prefix) const;
};

// The fe-classic bins of an FeSoil (FeBinSoilFromFeSoil) with the FE numerics of `options`, as
// the FeSoil entry points below and the virtual bevameter build them. Throws InputError naming
// "soil.<field>".
FeSoilBinFactory FeClassicBins(const FeSoil& soil, const RigOptions& options);

// One record per output interval (every step is too many).
struct RigSample {
  double time_s = 0;
  int phase = 0;                 // 1..4 as in the procedure; 5 constant slip; 6 towed
  double slip = 0;               // 1 - V / (omega R); 0 while settling
  double forward_speed_m_s = 0;
  double angular_speed_rad_s = 0;
  double drawbar_pull_n = 0;     // soil force on the wheel along +x (whole wheel)
  double torque_nm = 0;          // torque the drive must supply
  double vertical_force_n = 0;   // soil force on the wheel along +z (whole wheel)
  double sinkage_m = 0;          // depth of the wheel's lowest point below the undisturbed surface
};

struct RigRun {
  std::vector<RigSample> samples;
  int elements = 0;
  int nodes = 0;
  double element_size_m = 0;
  double time_step_s = 0;
  int steps = 0;
};

// A run stopped by its cancellation check: the CancelledError its callers know, with the records
// the run had taken by then, so that a study stopped part-way keeps what it measured.
class StoppedRunError : public CancelledError {
 public:
  explicit StoppedRunError(std::vector<RigSample> samples) : samples_(std::move(samples)) {}
  const std::vector<RigSample>& samples() const { return samples_; }

 private:
  std::vector<RigSample> samples_;
};

// Runs the procedure in a bin of `soil_bin`. Throws InputError for bad parameters,
// CannotCarryError when the wheel sinks to its axle, std::runtime_error when the bin fails (an
// element turns inside out), StoppedRunError (a CancelledError) when cancelled.
RigRun RunDrawbarPullTest(const SoilBinFactory& soil_bin, const RigWheel& wheel,
                          const DrawbarPullProcedure& procedure, const RigOptions& options);

// Phases 1-3, then the slip fixed at `slip` (omega held, V = (1 - s) omega R) for `hold_s`.
RigRun RunConstantSlipTest(const SoilBinFactory& soil_bin, const RigWheel& wheel, double slip,
                           double hold_s, const DrawbarPullProcedure& procedure,
                           const RigOptions& options);

// Phases 1-3, then towed for `hold_s`: the forward speed of phase 3 held and no torque on the
// wheel, which turns as the soil makes it (free rolling). Its drawbar pull is minus the motion
// resistance of free rolling, and its slip (negative: skid) the free-rolling slip.
RigRun RunTowedTest(const SoilBinFactory& soil_bin, const RigWheel& wheel, double hold_s,
                    const DrawbarPullProcedure& procedure, const RigOptions& options);

// The same on the fe-classic bin of an FeSoil: Drucker-Prager of soil.strength, rim friction
// tan(phi) and adhesion c, FE numerics from `options` (FeBinSoilFromFeSoil, FeSoilBinFactory).
RigRun RunDrawbarPullTest(const FeSoil& soil, const RigWheel& wheel,
                          const DrawbarPullProcedure& procedure, const RigOptions& options);
RigRun RunConstantSlipTest(const FeSoil& soil, const RigWheel& wheel, double slip, double hold_s,
                           const DrawbarPullProcedure& procedure, const RigOptions& options);
RigRun RunTowedTest(const FeSoil& soil, const RigWheel& wheel, double hold_s,
                    const DrawbarPullProcedure& procedure, const RigOptions& options);

// The traction curve at `slips` from a drawbar-pull run. Filtering: each requested slip s_k is the
// mean of the ramp samples with |s - s_k| <= w/2, w = max(0.05, spacing of the slips); s = 0 also
// takes the second half of the self-propelled phase. Torque gives gross traction T / R, motion
// resistance T / R - D and efficiency D (1 - s) R / T (0 where D <= 0).
std::vector<TractionPoint> CurveFromRun(const RigRun& run, const std::vector<double>& slips,
                                        double radius_m);

// The records as CSV, a header line and then one line per record in SI units (time_s, phase, slip,
// forward_speed_m_s, angular_speed_rad_s, drawbar_pull_n, torque_nm, vertical_force_n, sinkage_m):
// `gonogo-rig drawbar --samples`, `gonogo-fe-de --samples-csv`.
std::string RigSamplesCsv(const std::vector<RigSample>& samples);

}  // namespace gonogo::rig
