// The open-soil seam: a soil model declared in this file alone (no other edit anywhere) reaches
// validation, the cache key, the curve store and the wire.
#include <gtest/gtest.h>

#include <filesystem>

#include "cache/curve_key.h"
#include "cache/curve_store.h"
#include "cache/database.h"
#include "server/convert.h"
#include "solvers/common/errors.h"
#include "solvers/common/soil_model.h"

namespace gonogo::server {
namespace {

namespace fs = std::filesystem;

// A made-up model: a cohesive clay with an undrained strength and a sensitivity.
void DeclareTestClay() {
  if (SoilModels().Find("test-clay")) return;
  SoilModelSpec clay;
  clay.name = "test-clay";
  clay.description = "test model: undrained clay";
  clay.source = "this test";
  SoilParameterSpec su;
  su.name = "undrained_strength_pa";
  su.unit = "Pa";
  su.min = 0;
  su.max = 1e6;
  su.min_open = true;
  su.description = "undrained shear strength s_u";
  SoilParameterSpec st;
  st.name = "sensitivity";
  st.unit = "-";
  st.min = 1;
  st.max = 100;
  st.default_value = 4.0;
  st.description = "strength ratio undisturbed / remoulded";
  clay.parameters = {su, st};
  SoilModels().Register(clay);
}

TEST(SoilModelSeam, ANewModelReachesValidationKeyStorageAndTheWire) {
  DeclareTestClay();
  TractionRequest r;
  r.tyre = TyreGeometry{1.011, 0.335, 0.2178, 0.0327, 0.0};
  r.wheel_load_n = 13438;
  r.slips = {0, 0.5, 1};
  r.soil.parameters = SoilParameters{"test-clay", {{"undrained_strength_pa", 25000}}};

  // Validation: the declaration's range, named field.
  r.Validate();
  TractionRequest bad = r;
  bad.soil.parameters->values["undrained_strength_pa"] = -1;
  try {
    bad.Validate();
    FAIL() << "a negative strength passed";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "soil.parameters.undrained_strength_pa");
  }

  // Key: defaults filled, canonical text in the key; a different value, a different key.
  const TractionRequest q = cache::Quantise(r);
  EXPECT_DOUBLE_EQ(q.soil.parameters->Get("sensitivity"), 4.0);
  const std::string key = cache::CurveKey("t", "t-1", q);
  EXPECT_NE(key.find(";params=test-clay{sensitivity=4,undrained_strength_pa=25000};"),
            std::string::npos)
      << key;
  TractionRequest other = r;
  other.soil.parameters->values["sensitivity"] = 8;
  EXPECT_NE(cache::CurveKey("t", "t-1", cache::Quantise(other)), key);

  // Storage: a real SQLite file round trip.
  const fs::path dir = fs::temp_directory_path() / ("gonogo-seam-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    cache::Database db((dir / "gonogo.sqlite").string());
    cache::CurveStore store(db);
    cache::StoredCurve c;
    c.cache_key = key;
    c.request = q;
    c.curve.tier = "t";
    c.curve.tier_version = "t-1";
    for (double s : q.slips) c.curve.points.push_back({s, 100 * s, 10, 0.01, 0.2, 100, 0});
    c.computed_by = "thread";
    ASSERT_TRUE(store.Put(c));
    const auto back = store.Find(key);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(back->request.soil.parameters, q.soil.parameters);
    EXPECT_EQ(cache::CurveKey("t", "t-1", cache::Quantise(back->request)), key);
  }
  fs::remove_all(dir);

  // The wire: the generic message carries it both ways.
  const v1::SoilState wire = ToProto(q.soil);
  EXPECT_EQ(wire.parameters().model(), "test-clay");
  EXPECT_EQ(wire.parameters().values().at("undrained_strength_pa"), 25000);
  v1::SoilState reparsed;
  ASSERT_TRUE(reparsed.ParseFromString(wire.SerializeAsString()));
  EXPECT_EQ(FromProto(reparsed).parameters, q.soil.parameters);
}

TEST(SoilModelSeam, TheDeprecatedBekkerMessageIsAnAliasOfTheBekkerModel) {
  v1::SoilState wire;
  v1::BekkerParameters* b = wire.mutable_bekker();
  b->set_n(0.79);
  b->set_kc(102000);
  b->set_kphi(5301000);
  b->set_cohesion_pa(1300);
  b->set_friction_angle_deg(31.1);
  b->set_shear_deformation_m(0.0115);
  const SoilState soil = FromProto(wire);
  ASSERT_TRUE(soil.parameters.has_value());
  EXPECT_EQ(*soil.parameters,
            (BekkerParameters{0.79, 102000, 5301000, 1300, 31.1, 0.0115}.ToSoilModel()));
  // `parameters` wins over the alias; answers carry only `parameters`.
  wire.mutable_parameters()->set_model("dem-eepa");
  EXPECT_EQ(FromProto(wire).parameters->model, "dem-eepa");
  EXPECT_FALSE(ToProto(soil).has_bekker());
  EXPECT_EQ(ToProto(soil).parameters().model(), "bekker");
}

}  // namespace
}  // namespace gonogo::server
