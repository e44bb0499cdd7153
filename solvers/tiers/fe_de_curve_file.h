// An fe-de curve kept in a file with the configuration it was run on. A default-configuration
// fe-de curve takes most of a day here (checkpointed, resumed over several runs: gonogo-fe-de
// --checkpoint-dir), so it is computed once and kept: `gonogo-fe-de --curve-csv FILE` writes it,
// `gonogo-bench-fe-ann --fe-de-curve FILE` compares an fe-ann curve of the same rig with it.
//
// The file: one line "# gonogo-fe-de curve: key=value key=value ..." (tier, soil, preset,
// overrides, wheel_diameter_m, wheel_width_m, wheel_load_n, elements, fe_steps, wall_s_this_run:
// a resumed run counts from its resumption), then the
// CSV of `gonogo curve --csv`'s columns (slip, drawbar_pull_n, torque_nm, sinkage_m,
// tractive_efficiency, gross_traction_n, motion_resistance_n).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "solvers/common/traction.h"

namespace gonogo::tiers {

struct FeDeCurveFile {
  std::map<std::string, std::string> configuration;  // the first line's key=value words
  std::vector<TractionPoint> points;                 // in the file's order (increasing slip)
};

// The words that say which rig a curve is of: tier (its version, which names the preset), soil,
// preset, overrides ("none", or the overridden options as name:value words joined by commas),
// wheel_diameter_m, wheel_width_m and wheel_load_n (numbers as %.17g). The writer adds elements,
// fe_steps and wall_s_this_run; a reader compares these.
std::map<std::string, std::string> FeDeRigConfiguration(const std::string& tier_version,
                                                        const std::string& soil,
                                                        const std::string& preset,
                                                        const std::string& overrides,
                                                        const TractionRequest& request);

// A number as the configuration words write it (%.17g).
std::string ConfigurationNumber(double value);

// The file's text (written whole; the caller renames it into place).
std::string FeDeCurveFileText(const FeDeCurveFile& file);

// Reads `path`. Throws InputError naming `field` and the line for a missing file, a missing or
// malformed configuration line, a header other than the one above, or a row that is not seven
// finite numbers.
FeDeCurveFile ReadFeDeCurveFile(const std::string& path, const std::string& field);

// Checks that `file` was run with `expected` (each key present and equal as text, numbers
// compared as numbers to 1e-9 relative) and at exactly the slips `slips`; throws InputError
// naming `field`, the key and both values otherwise.
void RequireFeDeConfiguration(const FeDeCurveFile& file,
                              const std::map<std::string, std::string>& expected,
                              const std::vector<double>& slips, const std::string& field);

}  // namespace gonogo::tiers
