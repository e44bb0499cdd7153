#include "cache/curve_store.h"

#include <cstdio>
#include <cstring>
#include <sstream>

#include "cache/curve_key.h"
#include "solvers/mobility/similarity.h"

namespace gonogo::cache {

namespace {

// Points are stored as a packed array of doubles, kFields per point, in TractionPoint's field order.
constexpr int kFields = 7;

std::string PackPoints(const std::vector<TractionPoint>& points) {
  std::vector<double> flat;
  flat.reserve(points.size() * kFields);
  for (const TractionPoint& p : points) {
    flat.insert(flat.end(), {p.slip, p.drawbar_pull_n, p.torque_nm, p.sinkage_m,
                             p.tractive_efficiency, p.gross_traction_n, p.motion_resistance_n});
  }
  return std::string(reinterpret_cast<const char*>(flat.data()), flat.size() * sizeof(double));
}

std::vector<TractionPoint> UnpackPoints(const std::string& blob) {
  const size_t n = blob.size() / (kFields * sizeof(double));
  std::vector<double> flat(n * kFields);
  std::memcpy(flat.data(), blob.data(), flat.size() * sizeof(double));
  std::vector<TractionPoint> points(n);
  for (size_t i = 0; i < n; ++i) {
    const double* f = &flat[i * kFields];
    points[i] = TractionPoint{f[0], f[1], f[2], f[3], f[4], f[5], f[6]};
  }
  return points;
}

// The stored canonical text of a curve's soil parameters; "" gives none.
std::optional<SoilParameters> ParseStoredParameters(const std::string& text) {
  try {
    return ParseCanonicalText(text);
  } catch (const std::invalid_argument&) {
    throw DatabaseError("unreadable soil parameters in the curve cache: " + text);
  }
}

// A surrogate run as one line of "name=value" words, the fallback steps comma-separated:
// "fe_steps=900 fallbacks=2 at=449,637 below_floor=0 beyond_distance=2 beyond_spread=0 returns=0
// unanswered=0 kept=2 updates=114041 network_s=2.28 fallback_s=1.01"; "" for a curve without one.
// A line written before a figure existed reads it as 0 (below_floor, beyond_distance,
// beyond_spread).
std::string SurrogateRunText(const std::optional<SurrogateRun>& run) {
  if (!run) return "";
  std::ostringstream out;
  out.precision(17);
  out << "fe_steps=" << run->fe_steps << " fallbacks=" << run->fallbacks << " at=";
  for (std::size_t k = 0; k < run->fallback_point_steps.size(); ++k) {
    out << (k ? "," : "") << run->fallback_point_steps[k];
  }
  out << " below_floor=" << run->fallbacks_flagged.below_pressure_floor
      << " beyond_distance=" << run->fallbacks_flagged.beyond_distance
      << " beyond_spread=" << run->fallbacks_flagged.beyond_spread << " returns=" << run->returns
      << " unanswered=" << run->unanswered_flags << " kept=" << run->fallback_paths_kept
      << " updates=" << run->network_point_updates << " network_s=" << run->network_seconds
      << " fallback_s=" << run->fallback_seconds;
  return out.str();
}

std::optional<SurrogateRun> ParseSurrogateRunText(const std::string& text) {
  if (text.empty()) return std::nullopt;
  SurrogateRun run;
  std::istringstream words(text);
  std::string word;
  try {
    while (words >> word) {
      const std::size_t equals = word.find('=');
      if (equals == std::string::npos) throw std::invalid_argument(word);
      const std::string name = word.substr(0, equals), value = word.substr(equals + 1);
      if (name == "fe_steps") run.fe_steps = std::stoll(value);
      else if (name == "fallbacks") run.fallbacks = std::stoi(value);
      else if (name == "returns") run.returns = std::stoll(value);
      else if (name == "below_floor")
        run.fallbacks_flagged.below_pressure_floor = std::stoi(value);
      else if (name == "beyond_distance")
        run.fallbacks_flagged.beyond_distance = std::stoi(value);
      else if (name == "beyond_spread")
        run.fallbacks_flagged.beyond_spread = std::stoi(value);
      else if (name == "unanswered") run.unanswered_flags = std::stoll(value);
      else if (name == "kept") run.fallback_paths_kept = std::stoi(value);
      else if (name == "updates") run.network_point_updates = std::stoll(value);
      else if (name == "network_s") run.network_seconds = std::stod(value);
      else if (name == "fallback_s") run.fallback_seconds = std::stod(value);
      else if (name == "at") {
        std::istringstream steps(value);
        std::string step;
        while (std::getline(steps, step, ',')) run.fallback_point_steps.push_back(std::stoll(step));
      }
      // A name this code does not know is a later version's figure: left out.
    }
  } catch (const std::logic_error&) {  // std::invalid_argument, std::out_of_range
    throw DatabaseError("unreadable surrogate run in the curve cache: " + text);
  }
  return run;
}

constexpr char kColumns[] =
    "id, cache_key, tier, tier_version, soil_name, cone_index_pa, diameter_m, width_m, "
    "section_height_m, deflection_m, rolling_radius_m, wheel_load_n, points, computed_by, "
    "compute_seconds, computed_unix_ms, soil_parameters, inflation_pressure_pa, immobile_reason, "
    "surrogate_run";
constexpr int kColumnCount = 20;  // FindSimilar reads its pi-terms after them

StoredCurve ReadRow(const Statement& s) {
  StoredCurve c;
  c.cache_key = s.Text(1);
  c.curve.tier = s.Text(2);
  c.curve.tier_version = s.Text(3);
  c.request.soil.soil_name = s.Text(4);
  c.request.soil.cone_index_pa = s.Double(5);
  c.request.tyre = TyreGeometry{s.Double(6), s.Double(7), s.Double(8), s.Double(9), s.Double(10)};
  c.request.wheel_load_n = s.Double(11);
  c.curve.points = UnpackPoints(s.Blob(12));
  for (const TractionPoint& p : c.curve.points) c.request.slips.push_back(p.slip);
  c.computed_by = s.Text(13);
  c.compute_seconds = s.Double(14);
  c.computed_unix_ms = s.Int(15);
  c.request.soil.parameters = ParseStoredParameters(s.Text(16));
  c.request.tyre.inflation_pressure_pa = s.Double(17);
  c.curve.immobile_reason = s.Text(18);
  c.curve.surrogate_run = ParseSurrogateRunText(s.Text(19));
  c.request.surrogate_model = SurrogateModelOfKey(c.cache_key);  // (the key is its only record)
  return c;
}

}  // namespace

std::optional<StoredCurve> CurveStore::Find(const std::string& key) {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare(std::string("SELECT ") + kColumns + " FROM curves WHERE cache_key = ?");
  s.Bind(1, key);
  if (!s.Step()) return std::nullopt;
  return ReadRow(s);
}

bool CurveStore::Put(const StoredCurve& c) {
  WriteTransaction tx(db_);
  Statement s = db_.Prepare(
      "INSERT OR IGNORE INTO curves (cache_key, tier, tier_version, soil_name, cone_index_pa, "
      "diameter_m, width_m, section_height_m, deflection_m, rolling_radius_m, wheel_load_n, points, "
      "computed_by, compute_seconds, computed_unix_ms, soil_parameters, inflation_pressure_pa, "
      "similarity_group, pi_b_over_d, pi_delta_over_h, pi_load_over_bd_pa, immobile_reason, "
      "surrogate_run) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)");
  const std::string blob = PackPoints(c.curve.points);
  s.Bind(1, c.cache_key).Bind(2, c.curve.tier).Bind(3, c.curve.tier_version);
  s.Bind(4, c.request.soil.soil_name).Bind(5, c.request.soil.cone_index_pa);
  s.Bind(6, c.request.tyre.diameter_m).Bind(7, c.request.tyre.width_m);
  s.Bind(8, c.request.tyre.section_height_m).Bind(9, c.request.tyre.deflection_m);
  s.Bind(10, c.request.tyre.RollingRadius()).Bind(11, c.request.wheel_load_n);
  s.BindBlob(12, blob.data(), blob.size());
  s.Bind(13, c.computed_by).Bind(14, c.compute_seconds).Bind(15, c.computed_unix_ms);
  s.Bind(16, CanonicalText(c.request.soil.parameters));
  s.Bind(17, c.request.tyre.inflation_pressure_pa);
  const mobility::PiTerms pi = mobility::ComputePiTerms(c.request);
  s.Bind(18, Scoped(c.scope, SimilarityGroup(c.curve.tier, c.curve.tier_version, c.request)));
  s.Bind(19, pi.width_over_diameter).Bind(20, pi.deflection_over_height);
  s.Bind(21, pi.load_over_bd_pa).Bind(22, c.curve.immobile_reason);
  s.Bind(23, SurrogateRunText(c.curve.surrogate_run));
  s.Run();
  const bool written = db_.Changes() > 0;
  tx.Commit();
  return written;
}

std::optional<StoredCurve> CurveStore::FindSimilar(const std::string& group,
                                                   const TractionRequest& q, double tolerance,
                                                   double min_scale_ratio) {
  const mobility::PiTerms want = mobility::ComputePiTerms(q);
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare(std::string("SELECT ") + kColumns +
                            ", pi_b_over_d, pi_delta_over_h, pi_load_over_bd_pa FROM curves "
                            "WHERE similarity_group = ? AND pi_load_over_bd_pa BETWEEN ? AND ?");
  s.Bind(1, group).Bind(2, want.load_over_bd_pa * (1 - tolerance));
  s.Bind(3, want.load_over_bd_pa * (1 + tolerance));
  std::optional<StoredCurve> best;
  double best_ratio = 0;
  while (s.Step()) {
    const mobility::PiTerms have{s.Double(kColumnCount), s.Double(kColumnCount + 1),
                                 s.Double(kColumnCount + 2)};
    if (!mobility::PiTermsMatch(want, have, tolerance)) continue;
    const double d = s.Double(6);
    const double ratio = std::min(d, q.tyre.diameter_m) / std::max(d, q.tyre.diameter_m);
    if (ratio < min_scale_ratio || ratio <= best_ratio) continue;
    best = ReadRow(s);
    best_ratio = ratio;
  }
  return best;
}

CurvePage CurveStore::List(const CurveFilter& f, int page_size, int64_t before_id) {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare(
      std::string("SELECT ") + kColumns +
      " FROM curves WHERE (?1 = '' OR tier = ?1) AND (?2 = '' OR soil_name = ?2)"
      " AND (?3 <= 0 OR cone_index_pa >= ?3) AND (?4 <= 0 OR cone_index_pa <= ?4)"
      " AND (?5 <= 0 OR id < ?5) AND (?7 = '' OR substr(cache_key, 1, length(?7)) = ?7)"
      " ORDER BY id DESC LIMIT ?6");
  s.Bind(1, f.tier).Bind(2, f.soil_name).Bind(3, f.min_cone_index_pa).Bind(4, f.max_cone_index_pa);
  s.Bind(5, before_id).Bind(6, static_cast<int64_t>(page_size + 1)).Bind(7, f.key_prefix);
  CurvePage page;
  int64_t last_id = 0;
  while (s.Step()) {
    if (static_cast<int>(page.curves.size()) == page_size) {
      page.next_after_id = last_id;
      break;
    }
    page.curves.push_back(ReadRow(s));
    last_id = s.Int(0);
    page.row_ids.push_back(last_id);
  }
  return page;
}

int64_t CurveStore::Count() {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare("SELECT COUNT(*) FROM curves");
  s.Step();
  return s.Int(0);
}

}  // namespace gonogo::cache
