// Empirical single-wheel traction of a pneumatic tyre from the cone index: the WES mobility number
// and the Brixius (1987) traction equations, plus the ERDC Vehicle-Terrain Interface (VTI) sinkage
// relation for fine-grained soil. Pure functions; every ratio is dimensionless and referred to the
// vertical wheel load W. Equations and sources are listed in solvers/terramech/README.md.
//
// Sources
//   [B87]  Brixius, W.W. (1987) Traction prediction equations for bias ply tires. ASAE Paper
//          87-1622. Also ASAE/ASABE D497 (Agricultural machinery management data) and
//          Wong, J.Y., Theory of Ground Vehicles, section on empirical methods. The equation
//          numbers (16), (17), (19)-(21) below follow the transcription in Pan, Papelis & He
//          (2004), "A vehicle-terrain system modeling and simulation approach to mobility analysis
//          of vehicles on soft terrain", Proc. SPIE 5422, 520-532.
//   [D18]  Dettwiller, I., Vahedifard, F., Rais-Rohani, M., Mason, G.L., Priddy, J.D. (2018)
//          Improving accuracy of vehicle-terrain interface algorithms for wheeled vehicles on
//          fine-grained soils through Bayesian calibration. J. Terramechanics 77, 59-68.
#pragma once

#include "solvers/common/traction.h"

namespace gonogo::terramech {

// ---- Brixius (1987) constants, bias-ply tyre [B87] ----
inline constexpr double kBrixiusTractionScale = 0.88;    // asymptote of (GT - 0.04 W)/W
inline constexpr double kBrixiusMobilityRate = 0.1;      // exponent on Bn
inline constexpr double kBrixiusSlipRate = 7.5;          // exponent on slip
inline constexpr double kBrixiusTyreLossRatio = 0.04;    // internal tyre loss, in GT/W and MR/W
inline constexpr double kBrixiusSlipResistance = 0.5;    // slip term of MR/W, 0.5 s / sqrt(Bn)
inline constexpr double kBrixiusDeflectionWeight = 5.0;  // (1 + 5 delta/h)
inline constexpr double kBrixiusAspectWeight = 3.0;      // (1 + 3 b/d)

// Cap on MR/W. Brixius' 1/Bn term diverges as the soil strength goes to zero; past MR = W the wheel
// is immobile whatever the exact value, so the motion resistance ratio is limited to 1 (active only
// for Bn below about 2, far outside the data the equations were fitted to).
inline constexpr double kMaxMotionResistanceRatio = 1.0;

// Brixius mobility number, eq. (17) of [B87]:
//   Bn = (CI b d / W) (1 + 5 delta/h) / (1 + 3 b/d).
// Dimensionless: CI in Pa, b and d in m, W in N. Zero when the cone index is zero.
// Throws InputError for a negative or non-finite cone index, a bad tyre or a non-positive load.
double MobilityNumber(double cone_index_pa, const TyreGeometry& tyre, double wheel_load_n);

// Gross traction ratio GT/W = T/(r W), eq. (21) of [B87]:
//   GT/W = 0.88 (1 - exp(-0.1 Bn)) (1 - exp(-7.5 s)) + 0.04.
double GrossTractionRatio(double mobility_number, double slip);

// Motion resistance ratio MR/W, eqs. (19)-(20) of [B87], capped at kMaxMotionResistanceRatio:
//   MR/W = 1/Bn + 0.04 + 0.5 s / sqrt(Bn).
// Bn = 0 returns the cap.
double MotionResistanceRatio(double mobility_number, double slip);

// Net traction (drawbar pull) ratio NT/W = GT/W - MR/W.
double NetTractionRatio(double mobility_number, double slip);

// Tractive efficiency TE = (NT/GT)(1 - s), 0 where NT <= 0. Lies in [0, 1 - s].
double TractiveEfficiency(double mobility_number, double slip);

// All Brixius ratios at one slip.
struct BrixiusRatios {
  double gross_traction = 0;     // GT/W
  double motion_resistance = 0;  // MR/W
  double net_traction = 0;       // NT/W
  double tractive_efficiency = 0;
};
BrixiusRatios EvaluateBrixius(double mobility_number, double slip);

// ---- ERDC VTI fine-grained sinkage [D18] ----

// Fine-grained sinkage numeric, [D18] eq. (3): N_cz = CI b d / (W (1 - delta/h)^(3/2)).
double FineGrainedSinkageNumeric(double cone_index_pa, const TyreGeometry& tyre,
                                 double wheel_load_n);

// Fine-grained numeric, [D18] eq. (1): N_c = N_cz / (1 + b/d)^(3/4).
double FineGrainedNumeric(double sinkage_numeric, const TyreGeometry& tyre);

// Self-propelled slip, [D18] eq. (2): S_sp = 21 / N_c^2.5 + 0.005. Infinite when N_c = 0.
double SelfPropelledSlip(double fine_grained_numeric);

// Relative sinkage z/d of a powered wheel, [D18] eq. (21):
//   z/d = 1.64 / (N_cz / S_sp^0.19)^1.21,
// clamped to [0, 1]: z = d is a fully buried tyre, the limit for N_cz -> 0 (zero cone index).
double PoweredSinkageRatio(double sinkage_numeric, double fine_grained_numeric);

// Sinkage of a powered wheel in metres: d * PoweredSinkageRatio(...). Does not vary with slip.
double PoweredSinkage(double cone_index_pa, const TyreGeometry& tyre, double wheel_load_n);

}  // namespace gonogo::terramech
