#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "accuracy/estimate.hpp"

namespace crackle::accuracy {
namespace {

// Q(h) = Q* + c h^p exactly: the observed order is p and the extrapolation is exact, so the
// estimate is the true error times the safety factor (effectivity 1.25).
TEST(ThreeLevel, ExactPowerLawGivesTheOrderAndTheTrueErrorTimesTheSafetyFactor) {
  const double exact = 0.1547, c = -0.04;
  for (double p : {1.0, 2.0, 3.5}) {
    auto q = [&](double h) { return exact + c * std::pow(h, p); };
    const Component component = three_level("mesh", q(1.0), q(0.5), q(0.25), 2.0, 0.5, 8.0);
    EXPECT_NEAR(component.observed_order, p, 1e-9);
    EXPECT_TRUE(component.verified);
    EXPECT_TRUE(component.asymptotic);
    const double true_error = (exact - q(0.25)) / q(0.25);
    EXPECT_NEAR(component.delta / true_error, kSafetyFactor, 1e-9);
  }
}

TEST(ThreeLevel, ARefinementThatDoesNotConvergeMonotonicallyIsNotVerified) {
  const Component oscillating = three_level("mesh", 1.0, 1.2, 1.1, 2.0, 0.5, 8.0);
  EXPECT_FALSE(oscillating.verified);
  EXPECT_FALSE(oscillating.asymptotic);
  EXPECT_NE(oscillating.reason.find("non-monotone"), std::string::npos);
  // The cautious estimate: three times the last change.
  EXPECT_NEAR(oscillating.delta, 3.0 * (1.1 - 1.2) / 1.1, 1e-12);

  const Component growing = three_level("mesh", 1.0, 1.01, 1.05, 2.0, 0.5, 8.0);
  EXPECT_FALSE(growing.verified);
  EXPECT_NE(growing.reason.find("not converging"), std::string::npos);
}

TEST(ThreeLevel, ALevelWithoutAValueIsNotVerifiedAndLeavesTheSumFinite) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Component missing = three_level("mesh", nan, 1.0, 1.01, 2.0, 0.5, 8.0);
  EXPECT_FALSE(missing.verified);
  EXPECT_NE(missing.reason.find("no finite value"), std::string::npos);
  const Estimate estimate = combine("f_b", 1.01, {missing, one_refinement("steps", 1.0, 1.01, 2.0, 2.0)});
  EXPECT_FALSE(estimate.verified);
  EXPECT_TRUE(std::isfinite(estimate.sum));
  EXPECT_GT(estimate.sum, 0.0);
}

TEST(ThreeLevel, AnOrderFarOutsideItsRangeIsNotVerifiedAndSlightlyOutsideIsCautious) {
  auto q = [](double h, double p) { return 1.0 + 0.1 * std::pow(h, p); };
  const Component slow = three_level("mesh", q(1, 0.4), q(0.5, 0.4), q(0.25, 0.4), 2.0, 0.5, 8.0);
  EXPECT_TRUE(slow.verified);
  EXPECT_FALSE(slow.asymptotic);
  EXPECT_EQ(slow.safety_factor, kCautiousSafetyFactor);
  const Component far = three_level("mesh", q(1, 0.1), q(0.5, 0.1), q(0.25, 0.1), 2.0, 0.5, 8.0);
  EXPECT_FALSE(far.verified);
}

TEST(OneRefinement, KnownOrderGivesTheErrorOfTheCoarserSetting) {
  // Newmark: Q(n) = Q* + c / n^2; n against 2n.
  const double exact = 2.0, c = 5.0;
  auto q = [&](double n) { return exact + c / (n * n); };
  const Component steps = one_refinement("steps", q(40), q(80), 2.0, 2.0);
  EXPECT_NEAR(steps.delta / ((exact - q(40)) / q(40)), kSafetyFactor, 1e-12);
  // Penalty: Q(k) = Q* + c / k; k against 4k.
  auto qk = [&](double k) { return exact + c / k; };
  const Component penalty = one_refinement("penalty", qk(10), qk(40), 4.0, 1.0);
  EXPECT_NEAR(penalty.delta / ((exact - qk(10)) / qk(10)), kSafetyFactor, 1e-12);
  // Unknown order: three times the change.
  const Component unknown = one_refinement("modes", 1.0, 1.01, 2.0, 0.0);
  EXPECT_NEAR(unknown.delta, 0.03, 1e-12);
}

TEST(Combine, SumIsConservativeRssIsTheQuadratureAndAFailingComponentMakesItUnverified) {
  std::vector<Component> components = {one_refinement("steps", 1.0, 1.0 + 0.03, 2.0, 2.0),
                                       one_refinement("penalty", 1.0, 1.0 - 0.04, 4.0, 1.0),
                                       residue("window", 1.0, 0.001)};
  Estimate estimate = combine("A2/A1", 1.0, components);
  const double d0 = components[0].delta, d1 = components[1].delta;
  EXPECT_NEAR(estimate.sum, std::abs(d0) + std::abs(d1) + 0.001, 1e-15);
  EXPECT_NEAR(estimate.rss, std::sqrt(d0 * d0 + d1 * d1 + 1e-6), 1e-15);
  EXPECT_TRUE(estimate.verified);
  EXPECT_LT(estimate.rss, estimate.sum);
  const std::string line = estimate_line(estimate);
  EXPECT_NE(line.find("A2/A1 = 1 ± "), std::string::npos) << line;
  EXPECT_NE(line.find("steps "), std::string::npos) << line;

  components.push_back(three_level("mesh", 1.0, 1.2, 1.1, 2.0, 0.5, 8.0));
  estimate = combine("A2/A1", 1.0, components);
  EXPECT_FALSE(estimate.verified);
  ASSERT_EQ(estimate.reasons.size(), 1u);
  EXPECT_NE(estimate_line(estimate).find("not verified: mesh: non-monotone"), std::string::npos);
}

}  // namespace
}  // namespace crackle::accuracy
