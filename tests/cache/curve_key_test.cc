#include "cache/curve_key.h"

#include <gtest/gtest.h>

#include <climits>
#include <cmath>

namespace gonogo::cache {
namespace {

TractionRequest Request() {
  TractionRequest r;
  r.soil.cone_index_pa = 149000;
  r.tyre = TyreGeometry{1.011, 0.335, 0.2178, 0.0327, 0};
  r.wheel_load_n = 13438.4;
  r.slips = TractionRequest::SlipSweep(0.05);
  return r;
}

TEST(ConeIndexBins, AdjacentBinsDifferByOnePercentAndRepresentativeIsClose) {
  for (double ci : {950.0, 22e3, 149e3, 3.1e6}) {
    const int bin = ConeIndexBin(ci);
    const double rep = ConeIndexOfBin(bin);
    EXPECT_LT(std::abs(rep / ci - 1.0), 0.0051) << ci;  // half a bin: sqrt(1.01) - 1
    EXPECT_NEAR(ConeIndexOfBin(bin + 1) / rep, 1.01, 2e-5);  // bins print to 0.01 Pa
    EXPECT_EQ(ConeIndexBin(rep), bin) << "the representative must fall in its own bin";
  }
  EXPECT_EQ(ConeIndexBin(0.0), INT_MIN);
  EXPECT_EQ(ConeIndexOfBin(INT_MIN), 0.0);
}

TEST(CurveKey, QuantiseIsIdempotentAndKeysAreStable) {
  const TractionRequest q = Quantise(Request());
  const TractionRequest qq = Quantise(q);
  EXPECT_EQ(CurveKey("empirical", "empirical-1", q), CurveKey("empirical", "empirical-1", qq));
  EXPECT_DOUBLE_EQ(q.wheel_load_n, 13438.0);
  EXPECT_NEAR(q.tyre.rolling_radius_m, 0.4728, 1e-12);
}

TEST(CurveKey, DerivedAndExplicitRollingRadiusShareAKey) {
  TractionRequest a = Request();
  TractionRequest b = Request();
  b.tyre.rolling_radius_m = a.tyre.RollingRadius();
  EXPECT_EQ(CurveKey("empirical", "e1", Quantise(a)), CurveKey("empirical", "e1", Quantise(b)));
}

TEST(CurveKey, EveryInputChangesTheKey) {
  const std::string base = CurveKey("empirical", "e1", Quantise(Request()));
  EXPECT_NE(base, CurveKey("empirical", "e2", Quantise(Request()))) << "tier version";
  EXPECT_NE(base, CurveKey("bekker", "e1", Quantise(Request()))) << "tier";
  TractionRequest r = Request();
  r.soil.cone_index_pa *= 1.02;
  EXPECT_NE(base, CurveKey("empirical", "e1", Quantise(r))) << "cone index";
  r = Request();
  r.wheel_load_n += 2;
  EXPECT_NE(base, CurveKey("empirical", "e1", Quantise(r))) << "load";
  r = Request();
  r.tyre.width_m += 0.001;
  EXPECT_NE(base, CurveKey("empirical", "e1", Quantise(r))) << "width";
  r = Request();
  r.slips = TractionRequest::SlipSweep(0.1);
  EXPECT_NE(base, CurveKey("empirical", "e1", Quantise(r))) << "slips";
  r = Request();
  r.soil.soil_name = "LETE sand";
  EXPECT_NE(base, CurveKey("empirical", "e1", Quantise(r))) << "soil";
  r = Request();
  r.tyre.inflation_pressure_pa = 200e3;
  EXPECT_NE(base, CurveKey("empirical", "e1", Quantise(r))) << "inflation pressure";
  r = Request();
  r.soil.parameters = BekkerParameters{0.7, 5270, 1515040, 1300, 31.1, 0.0115}.ToSoilModel();
  const std::string with_bekker = CurveKey("bekker", "b1", Quantise(r));
  r.soil.parameters->values["kphi"] *= 1.0001;
  EXPECT_NE(with_bekker, CurveKey("bekker", "b1", Quantise(r))) << "Bekker parameters";
  r = Request();
  r.surrogate_model = "sand-mlp-1";
  EXPECT_NE(base, CurveKey("empirical", "e1", Quantise(r))) << "surrogate model";
  EXPECT_NE(SimilarityGroup("empirical", "e1", Quantise(Request())),
            SimilarityGroup("empirical", "e1", Quantise(r)))
      << "surrogate model";
  // Without a model the key is what it was before models existed: stored curves stay found.
  EXPECT_EQ(base.find(";model="), std::string::npos);
  EXPECT_EQ(SurrogateModelOfKey(base), "");
  EXPECT_EQ(SurrogateModelOfKey(CurveKey("fe-ann", "a1", Quantise(r))), "sand-mlp-1");
}

}  // namespace
}  // namespace gonogo::cache
