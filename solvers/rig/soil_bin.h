// What the rig's procedures need from a soil bin, whatever fills it: an FE continuum over any
// constitutive model (fe_soil_bin.h) today, a DEM bin of particles later. The procedures (the
// drawbar-pull test of seed 001 section 6.3 in wheel_rig.h, the virtual bevameter in bevameter.h)
// run over this interface only, the way Chrono's ChWheelTestRig runs over rigid, SCM or granular
// terrain.
//
// Frame: x along the wheel's travel, y across it, z up; the undisturbed surface is z = 0 and the
// soil lies below. A procedure asks a SoilBinFactory for a bin of a layout, lets it settle, then
// per time step: sets the damping, applies its wheel or flat tool (forces for the coming step),
// steps, and reads the reactions. Forces and torques are those of the whole wheel or tool, even
// where the bin models only a symmetric part of it.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

namespace gonogo::rig {

using Vec3 = Eigen::Vector3d;

// --- the wheel ----------------------------------------------------------------------------------

// A rigid cylinder with its axle along y, rolling on the line y = 0.
struct WheelMotion {
  Vec3 centre_m = Vec3::Zero();
  Vec3 velocity_m_s = Vec3::Zero();
  double angular_velocity_rad_s = 0;  // about +y; > 0 rolls towards +x
};

// What the soil does to the wheel in one step.
struct WheelLoad {
  Vec3 force_n = Vec3::Zero();  // resultant on the wheel
  double moment_y_nm = 0;       // about the axle, +y
  int nodes_in_contact = 0;     // FE surface nodes, DEM particles ... (diagnostic)
};

// The bin a wheel runs in: a box from x = 0 to length_m, centred on y = 0, down to -depth_m.
// resolution_m holds within path_half_width_m of y = 0 and fine_depth_m of the surface (FE: the
// element size; a DEM bin would read it as its particle-size scale); the bin may coarsen outside.
struct WheelBinLayout {
  double length_m = 0;
  double width_m = 0;  // whole width
  double depth_m = 0;
  double resolution_m = 0;
  double path_half_width_m = 0;
  double fine_depth_m = 0;
  double wheel_radius_m = 0;  // for the contact's own stable step
  double wheel_width_m = 0;
};

// --- flat tools (bevameter plates and shear rings) ----------------------------------------------

// The bin a flat tool works in: |x|, |y| <= half_extent_m around the tool's centre at the
// origin, down to -depth_m; resolution_m within fine_extent_m of the centre and of the surface.
// A tool that only pushes down is axisymmetric, so `turning_tool` false lets the bin model a
// quarter (x, y >= 0); a turning tool needs the whole box.
struct ToolBinLayout {
  double half_extent_m = 0;
  double fine_extent_m = 0;
  double depth_m = 0;
  double resolution_m = 0;
  bool turning_tool = false;
};

// A flat annulus inner_radius_m <= r <= outer_radius_m on the surface, centred at the origin
// (inner radius 0: a plate). Area and its first moment are of the soil surface it grips (the
// bin's discretisation of it), whole tool.
struct FlatTool {
  int id = 0;
  double area_m2 = 0;
  double area_moment_m3 = 0;  // sum of area x radius
};

// How a flat tool moves in the coming step.
struct FlatToolDrive {
  enum class Vertical {
    kSpeed,     // pushed down at vertical_speed_m_s; smooth (the soil slides freely under it)
    kPressure,  // pressed with load_fraction x normal_pressure_pa, free to sink
  };
  enum class InPlane {
    kFree,     // the soil under the tool moves freely in x and y
    kHeld,     // grips the soil and holds it (the ring being loaded)
    kTurning,  // grips the soil and turns about +z at angular_speed_rad_s
  };
  Vertical vertical = Vertical::kSpeed;
  double vertical_speed_m_s = 0;  // downwards positive
  double normal_pressure_pa = 0;
  double load_fraction = 1;       // of normal_pressure_pa, to bring the load on smoothly
  InPlane in_plane = InPlane::kFree;
  double angular_speed_rad_s = 0;
};

// What the tool does to the soil over the last step, whole tool.
struct FlatToolLoad {
  double normal_force_n = 0;  // pressing down (z < 0) on the soil; includes the tool nodes' inertia
  double torque_nm = 0;       // about +z, quasi-static (the gripped soil's inertia left out)
};

// --- the bin ------------------------------------------------------------------------------------

struct BinStepStatus {
  bool ok = true;
  std::string reason;  // when !ok: what failed (an element inside out, a material update ...)
};

struct SoilBinSize {
  int elements = 0;  // FE elements (a DEM bin: particles)
  int nodes = 0;     // FE nodes (a DEM bin: particles)
};

// One built bin. Not thread-safe; one procedure drives it.
class SoilBin {
 public:
  virtual ~SoilBin() = default;

  virtual SoilBinSize Size() const = 0;
  // The largest step that keeps the bin and its contacts stable, s.
  virtual double StableTimeStepS() const = 0;
  virtual double time_s() const = 0;
  // Numerical damping of the bin's motion, 1/s (FE: alpha of C = alpha M). Settling takes the
  // bin's own rate, which critically damps its first vertical mode; a rolling wheel wants less.
  virtual double SettlingDampingPerS() const = 0;
  virtual void SetDampingPerS(double damping_per_s) = 0;
  // Advances by dt_s. On failure nothing changed: the bin is as at the start of the step.
  virtual BinStepStatus Step(double dt_s) = 0;

  // Contact forces of the wheel for the coming step, and their reaction on the whole wheel;
  // `dt_s` advances the contact's history. Only bins made by MakeWheelBin; replaces the forces
  // of the last call.
  virtual WheelLoad ApplyWheel(const WheelMotion& wheel, double dt_s) = 0;

  // Flat tools, only on bins made by MakeToolBin. Throws InputError when the annulus covers no
  // part of the bin's surface.
  virtual FlatTool AttachFlatTool(double inner_radius_m, double outer_radius_m) = 0;
  virtual void DriveFlatTool(int tool, const FlatToolDrive& drive) = 0;
  // After a Step: what the tool did to the soil during it.
  virtual FlatToolLoad FlatToolReaction(int tool) const = 0;

  // Checkpoints, for procedures that outlast a process (the fe-de tier's drawbar-pull runs). The
  // bin's own state as bytes (SaveState) and its material points as checkpoint `generation` in a
  // directory (material/point_store.h, per rank where they are distributed): a bin built the same
  // way and restored from both continues bit for bit. Bins that cannot checkpoint throw
  // std::logic_error; RestoreState throws InputError for bytes of another bin.
  virtual std::string SaveState() const {
    throw std::logic_error("this soil bin cannot checkpoint");
  }
  virtual void RestoreState(const std::string& /*bytes*/) {
    throw std::logic_error("this soil bin cannot checkpoint");
  }
  virtual void WritePointCheckpoint(const std::string& /*directory*/,
                                    std::uint64_t /*generation*/) {
    throw std::logic_error("this soil bin cannot checkpoint");
  }
  virtual void ReadPointCheckpoint(const std::string& /*directory*/,
                                   std::uint64_t /*generation*/) {
    throw std::logic_error("this soil bin cannot checkpoint");
  }
};

// A soil the rig can build bins of: one per FE material, one per DEM packing, ...
// Thread-safe: each call builds its own bin.
class SoilBinFactory {
 public:
  virtual ~SoilBinFactory() = default;
  // For messages: "fe drucker-prager (lll_dry_sand)".
  virtual std::string Describe() const = 0;
  // Throw InputError for a layout the bin cannot build.
  virtual std::unique_ptr<SoilBin> MakeWheelBin(const WheelBinLayout& layout) const = 0;
  virtual std::unique_ptr<SoilBin> MakeToolBin(const ToolBinLayout& layout) const = 0;
};

}  // namespace gonogo::rig
