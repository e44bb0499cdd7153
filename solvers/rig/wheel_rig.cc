#include "solvers/rig/wheel_rig.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "solvers/common/byte_stream.h"
#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/material/checkpoint_files.h"
#include "solvers/rig/fe_soil_bin.h"

namespace gonogo::rig {
namespace {

using units::kPi;

// Wheel kinematics and load against time: phases 1-3, then one of three endings.
struct Schedule {
  enum class Ending {
    kSlipRamp,      // phase 4
    kConstantSlip,  // phase 5: `constant_slip` for `hold_s`
    kTowed,         // phase 6: forward speed held for `hold_s`, the wheel free to turn
  };
  DrawbarPullProcedure procedure;
  double radius_m = 0;
  Ending ending = Ending::kSlipRamp;
  double constant_slip = 0;
  double hold_s = 0;

  double RollingStart() const { return procedure.gravity_settle_s + procedure.load_settle_s; }
  double RampStart() const { return RollingStart() + procedure.self_propelled_s; }
  double Duration() const {
    return RampStart() + (ending == Ending::kSlipRamp ? procedure.slip_ramp_s : hold_s);
  }
  double AngularSpeed() const { return procedure.angular_speed_rad_s; }

  struct State {
    int phase = 1;
    double forward_speed_m_s = 0;
    double angular_speed_rad_s = 0;
    double load_fraction = 0;  // of W applied at the hub
  };

  State At(double t) const {
    State s;
    const double v0 = procedure.angular_speed_rad_s * radius_m;
    if (t < procedure.gravity_settle_s) return s;
    // The load comes on smoothly over the first half of the load settle, then holds.
    s.load_fraction =
        std::min(1.0, (t - procedure.gravity_settle_s) / (0.5 * procedure.load_settle_s));
    s.load_fraction = 0.5 - 0.5 * std::cos(kPi * s.load_fraction);
    if (t < RollingStart()) {
      s.phase = 2;
      return s;
    }
    s.load_fraction = 1;
    if (t < RampStart()) {
      s.phase = 3;
      const double up = std::min(1.0, (t - RollingStart()) / procedure.speed_ramp_up_s);
      s.forward_speed_m_s = v0 * (0.5 - 0.5 * std::cos(kPi * up));
      s.angular_speed_rad_s = s.forward_speed_m_s / radius_m;  // slip 0
      return s;
    }
    s.angular_speed_rad_s = AngularSpeed();
    if (ending == Ending::kTowed) {
      s.phase = 6;  // angular speed: set by the wheel's own rotation in Simulate
      s.forward_speed_m_s = v0;
    } else if (ending == Ending::kConstantSlip) {
      s.phase = 5;
      s.forward_speed_m_s = (1 - constant_slip) * v0;
    } else {
      s.phase = 4;
      s.forward_speed_m_s = v0 * std::max(0.0, 1 - (t - RampStart()) / procedure.slip_ramp_s);
    }
    return s;
  }

  double Travel() const {
    double travel = 0;
    const double dt = 1e-3;
    for (double t = 0; t < Duration(); t += dt) travel += At(t).forward_speed_m_s * dt;
    return travel;
  }
};

struct SampleSums {
  int count = 0;
  RigSample sum;
  void Add(const RigSample& s) {
    ++count;
    sum.slip += s.slip;
    sum.forward_speed_m_s += s.forward_speed_m_s;
    sum.angular_speed_rad_s += s.angular_speed_rad_s;
    sum.drawbar_pull_n += s.drawbar_pull_n;
    sum.torque_nm += s.torque_nm;
    sum.vertical_force_n += s.vertical_force_n;
    sum.sinkage_m += s.sinkage_m;
  }
  RigSample Mean(double time_s, int phase) const {
    RigSample m = sum;
    const double k = 1.0 / count;
    m.time_s = time_s;
    m.phase = phase;
    m.slip *= k;
    m.forward_speed_m_s *= k;
    m.angular_speed_rad_s *= k;
    m.drawbar_pull_n *= k;
    m.torque_nm *= k;
    m.vertical_force_n *= k;
    m.sinkage_m *= k;
    return m;
  }
};

// What a drawbar-pull run keeps between steps besides its bin: written to rig.state beside the
// bin's point checkpoint, whose generation it names.
struct RunState {
  std::string fingerprint;  // the run this state belongs to
  std::uint64_t generation = 0;
  int next_step = 0;
  double hub_z_m = 0, hub_vz_m_s = 0, hub_x_m = 0, towed_angular_speed_rad_s = 0;
  SampleSums sums;
  std::vector<RigSample> samples;
  std::string bin_state;
};

constexpr char kRunStateTag[9] = "GNGRIG01";

void PutSample(ByteWriter& out, const RigSample& s) {
  out.Put(s.time_s);
  out.Put(static_cast<std::int32_t>(s.phase));
  for (double v : {s.slip, s.forward_speed_m_s, s.angular_speed_rad_s, s.drawbar_pull_n,
                   s.torque_nm, s.vertical_force_n, s.sinkage_m}) {
    out.Put(v);
  }
}

void GetSample(ByteReader& in, RigSample& s) {
  std::int32_t phase = 0;
  in.Get(s.time_s);
  in.Get(phase);
  s.phase = phase;
  for (double* v : {&s.slip, &s.forward_speed_m_s, &s.angular_speed_rad_s, &s.drawbar_pull_n,
                    &s.torque_nm, &s.vertical_force_n, &s.sinkage_m}) {
    in.Get(*v);
  }
}

std::string RunStateBytes(const RunState& state) {
  ByteWriter out;
  out.PutTag(kRunStateTag);
  out.PutBlob(state.fingerprint);
  out.Put(state.generation);
  out.Put(static_cast<std::int32_t>(state.next_step));
  for (double v : {state.hub_z_m, state.hub_vz_m_s, state.hub_x_m,
                   state.towed_angular_speed_rad_s}) {
    out.Put(v);
  }
  out.Put(static_cast<std::int32_t>(state.sums.count));
  PutSample(out, state.sums.sum);
  out.Put(static_cast<std::uint64_t>(state.samples.size()));
  for (const RigSample& sample : state.samples) PutSample(out, sample);
  out.PutBlob(state.bin_state);
  return out.Take();
}

// The state in `path` if it is one of the run `fingerprint`; nullopt otherwise (none, another
// run's, unreadable).
std::optional<RunState> ReadRunState(const std::string& path, const std::string& fingerprint) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return std::nullopt;
  std::ostringstream buffer;
  buffer << file.rdbuf();
  const std::string bytes = buffer.str();
  try {
    ByteReader in(bytes);
    in.ExpectTag(kRunStateTag);
    RunState state;
    in.GetBlob(state.fingerprint);
    if (state.fingerprint != fingerprint) return std::nullopt;
    in.Get(state.generation);
    std::int32_t next_step = 0, count = 0;
    in.Get(next_step);
    state.next_step = next_step;
    for (double* v : {&state.hub_z_m, &state.hub_vz_m_s, &state.hub_x_m,
                      &state.towed_angular_speed_rad_s}) {
      in.Get(*v);
    }
    in.Get(count);
    state.sums.count = count;
    GetSample(in, state.sums.sum);
    std::uint64_t samples = 0;
    in.Get(samples);
    Require(samples < (1u << 24), "state", "implausible sample count");
    state.samples.resize(samples);
    for (RigSample& sample : state.samples) GetSample(in, sample);
    in.GetBlob(state.bin_state);
    return state;
  } catch (const InputError&) {
    return std::nullopt;
  }
}

RigRun Simulate(const SoilBinFactory& soil_bin, const RigWheel& wheel, const Schedule& schedule,
                const RigOptions& options) {
  wheel.Validate("wheel.");
  schedule.procedure.Validate("procedure.");
  options.Validate("rig.");
  const double radius = wheel.radius_m;
  const double h =
      options.element_size_m > 0 ? options.element_size_m : radius / options.elements_per_radius;

  // The soil bin: room for the whole run plus 1.5 R at either end, soil flowing sideways and a
  // pressure bulb of a few widths below the wheel.
  WheelBinLayout layout;
  const double start_x = 1.5 * radius;
  layout.length_m = start_x + schedule.Travel() + 1.5 * radius;
  layout.width_m = 2 * (0.5 * wheel.width_m + std::max(2 * wheel.width_m, 0.6 * radius));
  layout.depth_m = std::max(3 * wheel.width_m, radius);
  layout.resolution_m = h;
  layout.path_half_width_m = std::min(0.5 * wheel.width_m + h, 0.5 * layout.width_m);
  layout.fine_depth_m = std::min(std::max(wheel.width_m, 2 * h), layout.depth_m);
  layout.wheel_radius_m = radius;
  layout.wheel_width_m = wheel.width_m;
  const std::unique_ptr<SoilBin> bin = soil_bin.MakeWheelBin(layout);
  const double dt = bin->StableTimeStepS();

  RigRun run;
  const SoilBinSize size = bin->Size();
  run.elements = size.elements;
  run.nodes = size.nodes;
  run.element_size_m = h;
  run.time_step_s = dt;
  const int steps = static_cast<int>(std::ceil(schedule.Duration() / dt));
  run.steps = steps;
  const int sample_every = std::max(1, static_cast<int>(std::lround(0.005 / dt)));

  // The hub: the wheel's load and mass, free vertically, with numerical damping c = m / tau on its
  // vertical speed (tau 10 ms settling, 50 ms rolling).
  const double load_n = wheel.load_n;
  const double mass_kg = load_n / units::kStandardGravityMps2;
  double hub_z_m = radius;  // touching the undisturbed surface
  double hub_vz_m_s = 0;
  double hub_x_m = start_x;
  // A towed wheel turns freely: I d(omega)/dt = -(torque the drive would have to supply),
  // I = m R^2 / 2 of a solid disc of the wheel's mass W / g.
  const double inertia_kg_m2 = 0.5 * mass_kg * radius * radius;
  double towed_angular_speed_rad_s = schedule.AngularSpeed();
  SampleSums sums;

  // Resume from a checkpoint of this very run, if there is one.
  const bool checkpointing = !options.checkpoint_dir.empty();
  const std::string state_path = options.checkpoint_dir + "/rig.state";
  std::ostringstream fingerprint;
  fingerprint.precision(17);
  fingerprint << soil_bin.Describe() << "|" << run.elements << "|" << run.nodes << "|" << dt
              << "|" << steps << "|" << radius << "|" << wheel.width_m << "|" << load_n << "|"
              << static_cast<int>(schedule.ending) << "|" << schedule.constant_slip << "|"
              << schedule.hold_s << "|" << schedule.Duration() << "|"
              << options.rolling_damping_per_s;
  int first_step = 0;
  std::uint64_t generation = 0;
  if (checkpointing) {
    if (std::optional<RunState> saved = ReadRunState(state_path, fingerprint.str())) {
      bin->RestoreState(saved->bin_state);
      bin->ReadPointCheckpoint(options.checkpoint_dir, saved->generation);
      generation = saved->generation;
      first_step = saved->next_step;
      hub_z_m = saved->hub_z_m;
      hub_vz_m_s = saved->hub_vz_m_s;
      hub_x_m = saved->hub_x_m;
      towed_angular_speed_rad_s = saved->towed_angular_speed_rad_s;
      sums = saved->sums;
      run.samples = std::move(saved->samples);
    }
  }
  auto last_checkpoint = std::chrono::steady_clock::now();

  for (int step = first_step; step < steps; ++step) {
    const double t = bin->time_s();
    Schedule::State state = schedule.At(t);
    if (state.phase == 6) state.angular_speed_rad_s = towed_angular_speed_rad_s;
    bin->SetDampingPerS(state.phase <= 2 ? bin->SettlingDampingPerS()
                                         : options.rolling_damping_per_s);
    WheelMotion motion;
    motion.centre_m = Vec3(hub_x_m, 0, hub_z_m);
    motion.velocity_m_s = Vec3(state.forward_speed_m_s, 0, hub_vz_m_s);
    motion.angular_velocity_rad_s = state.angular_speed_rad_s;
    const WheelLoad load = bin->ApplyWheel(motion, dt);
    const BinStepStatus status = bin->Step(dt);
    if (!status.ok) {
      throw std::runtime_error("rig on " + soil_bin.Describe() + ": the soil bin failed at t = " +
                               std::to_string(t) + " s (phase " + std::to_string(state.phase) +
                               "): " + status.reason);
    }
    const double tau_s = state.phase <= 2 ? 0.01 : 0.05;
    const double hub_az =
        (load.force_n.z() - state.load_fraction * load_n) / mass_kg - hub_vz_m_s / tau_s;
    hub_vz_m_s += dt * hub_az;
    hub_z_m += dt * hub_vz_m_s;
    hub_x_m += dt * state.forward_speed_m_s;
    if (state.phase == 6) towed_angular_speed_rad_s += dt * load.moment_y_nm / inertia_kg_m2;

    RigSample sample;
    sample.slip = state.phase >= 3 && state.angular_speed_rad_s > 0
                      ? 1 - state.forward_speed_m_s / (state.angular_speed_rad_s * radius)
                      : 0;
    sample.forward_speed_m_s = state.forward_speed_m_s;
    sample.angular_speed_rad_s = state.angular_speed_rad_s;
    sample.drawbar_pull_n = load.force_n.x();
    sample.torque_nm = -load.moment_y_nm;
    sample.vertical_force_n = load.force_n.z();
    sample.sinkage_m = radius - hub_z_m;
    sums.Add(sample);
    if (sample.sinkage_m >= 0.9 * radius) {
      throw CannotCarryError("wheel_load_n", "the wheel sank to its axle in the soil bin (" +
                                                 soil_bin.Describe() + "; sinkage " +
                                                 std::to_string(sample.sinkage_m) + " m at slip " +
                                                 std::to_string(sample.slip) + ")");
    }
    const Schedule::State next = schedule.At(bin->time_s());
    if (sums.count == sample_every || next.phase != state.phase || step + 1 == steps) {
      run.samples.push_back(sums.Mean(bin->time_s(), state.phase));
      sums = SampleSums();
    }
    if (step % options.poll_every_steps == 0) {
      if (options.cancelled && options.cancelled()) throw StoppedRunError(run.samples);
      if (options.progress) options.progress(static_cast<double>(step) / steps);
      const auto now = std::chrono::steady_clock::now();
      if (checkpointing && step + 1 < steps &&
          std::chrono::duration<double>(now - last_checkpoint).count() >=
              options.checkpoint_every_s) {
        // The points first (a new generation, the last two kept), then the run's own state,
        // which names that generation: a crash between the two resumes from the previous pair.
        RunState state;
        state.fingerprint = fingerprint.str();
        state.generation = ++generation;
        state.next_step = step + 1;
        state.hub_z_m = hub_z_m;
        state.hub_vz_m_s = hub_vz_m_s;
        state.hub_x_m = hub_x_m;
        state.towed_angular_speed_rad_s = towed_angular_speed_rad_s;
        state.sums = sums;
        state.samples = run.samples;
        state.bin_state = bin->SaveState();
        bin->WritePointCheckpoint(options.checkpoint_dir, state.generation);
        material::checkpoint::WriteFileAtomically(state_path, RunStateBytes(state));
        last_checkpoint = now;
        if (options.on_checkpoint) options.on_checkpoint(step + 1);
      }
    }
  }
  if (options.progress) options.progress(1.0);
  return run;
}

}  // namespace

void RigWheel::Validate(const std::string& p) const {
  Require(radius_m > 0 && std::isfinite(radius_m), p + "radius_m", "must be positive");
  Require(width_m > 0 && std::isfinite(width_m), p + "width_m", "must be positive");
  Require(load_n > 0 && std::isfinite(load_n), p + "load_n", "must be positive");
}

void DrawbarPullProcedure::Validate(const std::string& p) const {
  Require(gravity_settle_s > 0, p + "gravity_settle_s", "must be positive");
  Require(load_settle_s > 0, p + "load_settle_s", "must be positive");
  Require(self_propelled_s > 0, p + "self_propelled_s", "must be positive");
  Require(slip_ramp_s > 0, p + "slip_ramp_s", "must be positive");
  Require(speed_ramp_up_s > 0 && speed_ramp_up_s <= self_propelled_s, p + "speed_ramp_up_s",
          "must be positive and within the self-propelled phase");
  Require(angular_speed_rad_s > 0, p + "angular_speed_rad_s", "must be positive");
}

void RigOptions::Validate(const std::string& p) const {
  Require(element_size_m >= 0, p + "element_size_m", "must not be negative");
  Require(elements_per_radius >= 2, p + "elements_per_radius", "must be at least 2");
  Require(rolling_damping_per_s >= 0, p + "rolling_damping_per_s", "must not be negative");
  Require(threads >= 1, p + "threads", "must be at least 1");
  Require(poll_every_steps >= 1, p + "poll_every_steps", "must be at least 1");
  Require(checkpoint_every_s >= 0 && std::isfinite(checkpoint_every_s), p + "checkpoint_every_s",
          "must be a finite number of seconds >= 0");
}

FeSoilBinFactory FeClassicBins(const FeSoil& soil, const RigOptions& options) {
  soil.Validate("soil.");
  FeBinOptions fe_options;
  fe_options.hourglass_coefficient = options.hourglass_coefficient;
  fe_options.hourglass_viscosity = options.hourglass_viscosity;
  fe_options.time_step_safety = options.time_step_safety;
  fe_options.threads = options.threads;
  return FeSoilBinFactory(FeBinSoilFromFeSoil(soil), fe_options);
}

RigRun RunDrawbarPullTest(const SoilBinFactory& soil_bin, const RigWheel& wheel,
                          const DrawbarPullProcedure& procedure, const RigOptions& options) {
  Schedule schedule;
  schedule.procedure = procedure;
  schedule.radius_m = wheel.radius_m;
  return Simulate(soil_bin, wheel, schedule, options);
}

RigRun RunTowedTest(const SoilBinFactory& soil_bin, const RigWheel& wheel, double hold_s,
                    const DrawbarPullProcedure& procedure, const RigOptions& options) {
  Require(hold_s > 0, "hold_s", "must be positive");
  Schedule schedule;
  schedule.procedure = procedure;
  schedule.radius_m = wheel.radius_m;
  schedule.ending = Schedule::Ending::kTowed;
  schedule.hold_s = hold_s;
  return Simulate(soil_bin, wheel, schedule, options);
}

RigRun RunConstantSlipTest(const SoilBinFactory& soil_bin, const RigWheel& wheel, double slip,
                           double hold_s, const DrawbarPullProcedure& procedure,
                           const RigOptions& options) {
  Require(slip >= 0 && slip < 1, "slip", "must lie in [0, 1)");
  Require(hold_s > 0, "hold_s", "must be positive");
  Schedule schedule;
  schedule.procedure = procedure;
  schedule.radius_m = wheel.radius_m;
  schedule.ending = Schedule::Ending::kConstantSlip;
  schedule.constant_slip = slip;
  schedule.hold_s = hold_s;
  return Simulate(soil_bin, wheel, schedule, options);
}

RigRun RunDrawbarPullTest(const FeSoil& soil, const RigWheel& wheel,
                          const DrawbarPullProcedure& procedure, const RigOptions& options) {
  return RunDrawbarPullTest(FeClassicBins(soil, options), wheel, procedure, options);
}

RigRun RunConstantSlipTest(const FeSoil& soil, const RigWheel& wheel, double slip, double hold_s,
                           const DrawbarPullProcedure& procedure, const RigOptions& options) {
  return RunConstantSlipTest(FeClassicBins(soil, options), wheel, slip, hold_s, procedure,
                             options);
}

RigRun RunTowedTest(const FeSoil& soil, const RigWheel& wheel, double hold_s,
                    const DrawbarPullProcedure& procedure, const RigOptions& options) {
  return RunTowedTest(FeClassicBins(soil, options), wheel, hold_s, procedure, options);
}

std::vector<TractionPoint> CurveFromRun(const RigRun& run, const std::vector<double>& slips,
                                        double radius_m) {
  double spacing = 0;
  for (size_t k = 1; k < slips.size(); ++k) spacing = std::max(spacing, slips[k] - slips[k - 1]);
  const double half_window = 0.5 * std::max(0.05, spacing);
  double self_propelled_end = 0, self_propelled_start = 0;
  for (const RigSample& s : run.samples) {
    if (s.phase == 3) {
      if (self_propelled_start == 0) self_propelled_start = s.time_s;
      self_propelled_end = s.time_s;
    }
  }
  const double self_propelled_middle = 0.5 * (self_propelled_start + self_propelled_end);
  std::vector<TractionPoint> points;
  for (double slip : slips) {
    double d = 0, t = 0, z = 0;
    int count = 0;
    for (const RigSample& s : run.samples) {
      const bool in_ramp = s.phase == 4 && std::abs(s.slip - slip) <= half_window;
      const bool at_rest_slip = slip == 0 && s.phase == 3 && s.time_s > self_propelled_middle;
      if (!in_ramp && !at_rest_slip) continue;
      d += s.drawbar_pull_n;
      t += s.torque_nm;
      z += s.sinkage_m;
      ++count;
    }
    Require(count > 0, "slips", "a slip has no samples in the run (was it a drawbar-pull run?)");
    TractionPoint p;
    p.slip = slip;
    p.drawbar_pull_n = d / count;
    p.torque_nm = t / count;
    p.sinkage_m = z / count;
    p.gross_traction_n = p.torque_nm / radius_m;
    p.motion_resistance_n = p.gross_traction_n - p.drawbar_pull_n;
    p.tractive_efficiency = p.drawbar_pull_n > 0 && p.torque_nm > 0
                                ? p.drawbar_pull_n * (1 - slip) / p.gross_traction_n
                                : 0;
    points.push_back(p);
  }
  return points;
}

std::string RigSamplesCsv(const std::vector<RigSample>& samples) {
  std::string text =
      "time_s,phase,slip,forward_speed_m_s,angular_speed_rad_s,drawbar_pull_n,torque_nm,"
      "vertical_force_n,sinkage_m\n";
  char line[256];
  for (const RigSample& s : samples) {
    std::snprintf(line, sizeof line, "%.4f,%d,%.4f,%.4f,%.4f,%.2f,%.2f,%.2f,%.5f\n", s.time_s,
                  s.phase, s.slip, s.forward_speed_m_s, s.angular_speed_rad_s, s.drawbar_pull_n,
                  s.torque_nm, s.vertical_force_n, s.sinkage_m);
    text += line;
  }
  return text;
}

}  // namespace gonogo::rig
