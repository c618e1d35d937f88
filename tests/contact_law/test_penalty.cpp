#include <gtest/gtest.h>

#include <cmath>

#include "contact_law/penalty.hpp"

namespace crackle::contact {
namespace {

const Vec3 kNormal = Vec3::UnitZ();

TEST(Penalty, GapIsInitialGapPlusRelativeNormalDisplacement) {
  // eq. (9): g = g0 + (u- - u+) . n+
  EXPECT_DOUBLE_EQ(normal_gap(1e-3, Vec3(0.0, 0.0, -4e-4), Vec3(0.0, 0.0, 1e-4), kNormal), 5e-4);
  EXPECT_DOUBLE_EQ(normal_gap(0.0, Vec3(7.0, -3.0, 0.0), Vec3(1.0, 2.0, 0.0), kNormal), 0.0);  // tangential only
  const Vec3 tilted = Vec3(1.0, 1.0, 0.0).normalized();
  EXPECT_NEAR(normal_gap(-1e-6, Vec3(2e-6, 0.0, 0.0), Vec3::Zero(), tilted), -1e-6 + 2e-6 / std::sqrt(2.0), 1e-20);
}

TEST(Penalty, PressureOnlyInCompression) {
  EXPECT_EQ(penalty_pressure(1e-6, 1e12), 0.0);
  EXPECT_EQ(penalty_pressure(0.0, 1e12), 0.0);
  EXPECT_DOUBLE_EQ(penalty_pressure(-2e-6, 1e12), 2e6);
  EXPECT_DOUBLE_EQ(normal_penalty_energy(-2e-6, 1e12), 0.5 * 1e12 * 4e-12);
  EXPECT_EQ(normal_penalty_energy(3e-6, 1e12), 0.0);
}

TEST(Penalty, TangentialPartRemovesTheNormalComponent) {
  const Vec3 v(1.0, -2.0, 3.0);
  EXPECT_TRUE(tangential_part(v, kNormal).isApprox(Vec3(1.0, -2.0, 0.0)));
  const Vec3 n = Vec3(1.0, 2.0, 2.0) / 3.0;
  EXPECT_NEAR(tangential_part(v, n).dot(n), 0.0, 1e-15);
}

TEST(Coulomb, SticksInsideTheConeWithoutDissipation) {
  const double eps = 1e12, mu = 0.5, p = 1e6;  // limit mu p = 5e5 Pa
  const CoulombUpdate update = coulomb_return_mapping(Vec3(1e5, 0.0, 0.0), Vec3(-2e-7, 1e-7, 5e-7), kNormal, eps, mu, p);
  EXPECT_FALSE(update.slipping);
  // t = t_old - eps ds_T (the normal part of the increment is ignored), resisting the slip.
  EXPECT_TRUE(update.traction.isApprox(Vec3(1e5 + 2e5, -1e5, 0.0)));
  EXPECT_EQ(update.dissipation, 0.0);
}

TEST(Coulomb, SlipsOnTheConeAndDissipatesMuPTimesTheSlip) {
  const double eps = 1e12, mu = 0.5, p = 1e6, limit = mu * p;
  // Already sliding along -x: traction on the minus face +x at the limit; a further slip of 1e-6 m.
  const Vec3 old(limit, 0.0, 0.0);
  const CoulombUpdate update = coulomb_return_mapping(old, Vec3(-1e-6, 0.0, 0.0), kNormal, eps, mu, p);
  EXPECT_TRUE(update.slipping);
  EXPECT_TRUE(update.traction.isApprox(Vec3(limit, 0.0, 0.0)));
  EXPECT_NEAR(update.dissipation, limit * 1e-6, 1e-12 * limit * 1e-6);  // steady sliding: mu p |ds|
  // The traction stays on the cone and points against the slip whatever its direction.
  const CoulombUpdate turn = coulomb_return_mapping(old, Vec3(0.0, 3e-6, 0.0), kNormal, eps, mu, p);
  EXPECT_NEAR(turn.traction.norm(), limit, 1e-9 * limit);
  EXPECT_LT(turn.traction.y(), 0.0);
  EXPECT_GT(turn.dissipation, 0.0);
}

TEST(Coulomb, OpeningReleasesTheStoredTractionAsDissipation) {
  const double eps = 1e12;
  const Vec3 old(3e5, -4e5, 0.0);
  const CoulombUpdate update = coulomb_return_mapping(old, Vec3::Zero(), kNormal, eps, 0.5, 0.0);
  EXPECT_TRUE(update.traction.isZero());
  EXPECT_NEAR(update.dissipation, tangential_penalty_energy(old, eps), 1e-12);
}

TEST(Coulomb, StickLoadUnloadCycleDissipatesNothing) {
  const double eps = 1e12, mu = 0.5, p = 1e6;
  Vec3 traction = Vec3::Zero();
  double dissipated = 0.0;
  for (int k = 0; k < 20; ++k) {
    const Vec3 increment = (k < 10 ? 1.0 : -1.0) * Vec3(1e-8, 2e-8, 0.0);
    const CoulombUpdate update = coulomb_return_mapping(traction, increment, kNormal, eps, mu, p);
    EXPECT_FALSE(update.slipping);
    traction = update.traction;
    dissipated += update.dissipation;
  }
  EXPECT_NEAR(traction.norm(), 0.0, 1e-6);
  EXPECT_EQ(dissipated, 0.0);
}

TEST(ImplicitPair, SolvesThePenaltyLawAtTheEndOfTheStep) {
  const double eps = 1e13, compliance = 3e-19;  // end gap = free gap + compliance * p
  const PairResponse open = implicit_pair_response(2e-7, Vec3::Zero(), kNormal, Vec3::Zero(), compliance, compliance, eps, eps, 0.0);
  EXPECT_EQ(open.pressure, 0.0);
  EXPECT_EQ(open.gap, 2e-7);
  const PairResponse closed = implicit_pair_response(-2e-7, Vec3::Zero(), kNormal, Vec3::Zero(), compliance, compliance, eps, eps, 0.0);
  EXPECT_NEAR(closed.gap, -2e-7 + compliance * closed.pressure, 1e-22);   // consistent with the motion
  EXPECT_NEAR(closed.pressure, penalty_pressure(closed.gap, eps), 1e-9 * closed.pressure);  // eq. (25d) at the end
  EXPECT_GT(closed.gap, -2e-7);
}

TEST(ImplicitPair, FrictionSticksOrSlipsWithTheEndOfStepTraction) {
  const double eps = 1e13, compliance = 1e-19, mu = 0.3;
  const Vec3 old(1e5, 0.0, 0.0);
  // Small slip: stick, and the traction is the spring law of the slip it actually produces.
  const Vec3 small(-1e-9, 0.0, 0.0);
  const PairResponse stick = implicit_pair_response(-1e-6, small, kNormal, old, compliance, compliance, eps, eps, mu);
  EXPECT_FALSE(stick.slipping);
  const Vec3 slip = small + compliance * stick.traction;
  EXPECT_TRUE(stick.traction.isApprox(old - eps * slip, 1e-12));
  EXPECT_EQ(stick.dissipation, 0.0);
  // Large slip: on the cone mu p, against the slip, dissipating.
  const PairResponse slide = implicit_pair_response(-1e-6, Vec3(0.0, 1e-5, 0.0), kNormal, old, compliance, compliance, eps, eps, mu);
  EXPECT_TRUE(slide.slipping);
  EXPECT_NEAR(slide.traction.norm(), mu * slide.pressure, 1e-9 * slide.pressure);
  EXPECT_LT(slide.traction.y(), 0.0);
  EXPECT_GT(slide.dissipation, 0.0);
}

}  // namespace
}  // namespace crackle::contact
