#pragma once
// Timoshenko beam theory for reference frequencies of a clamped-free beam (test helper).
#include <Eigen/Dense>
#include <cmath>
#include <vector>

namespace crackle::modal::testing {

/// Rectangular cross-section b x t bending about the axis along b (displacement along t).
struct TimoshenkoBeam {
  double length = 1.0;
  double width = 0.1;      ///< b
  double thickness = 0.1;  ///< t, in the direction of the deflection
  double young = 2.1e11;
  double poisson = 0.3;
  double density = 7800.0;

  /// Determinant of the clamped-free boundary conditions at circular frequency omega. With
  /// w = C1 cosh(ax) + C2 sinh(ax) + C3 cos(bx) + C4 sin(bx), the rotation follows from
  /// kGA (w'' - psi') + rho A omega^2 w = 0; clamped: w = psi = 0 at x = 0; free: psi' = 0
  /// (moment) and w' - psi = 0 (shear force) at x = L. Valid below the cut-off rho I omega^2 < kGA.
  double clamped_free_determinant(double omega) const {
    const double area = width * thickness;
    const double inertia = width * thickness * thickness * thickness / 12.0;
    const double shear = young / (2.0 * (1.0 + poisson));
    const double kappa = 10.0 * (1.0 + poisson) / (12.0 + 11.0 * poisson);  // Cowper, rectangle
    const double kga = kappa * shear * area;
    const double w2 = omega * omega;
    const double q = density * area * w2 / kga;
    const double b4 = young * inertia * kga;
    const double b2 = kga * density * inertia * w2 + density * area * w2 * young * inertia;
    const double b0 = density * area * w2 * (density * inertia * w2 - kga);
    const double root = std::sqrt(b2 * b2 - 4.0 * b4 * b0);
    const double a = std::sqrt((-b2 + root) / (2.0 * b4));
    const double b = std::sqrt((b2 + root) / (2.0 * b4));
    const double alpha = a + q / a;
    const double beta = -b + q / b;
    const double x = length;
    const double ch = std::cosh(a * x), sh = std::sinh(a * x), c = std::cos(b * x), s = std::sin(b * x);
    Eigen::Matrix4d m;
    m << 1, 0, 1, 0,  //
        0, alpha, 0, -beta,  //
        alpha * a * ch, alpha * a * sh, beta * b * c, beta * b * s,  //
        (a - alpha) * sh, (a - alpha) * ch, -(b + beta) * s, (b + beta) * c;
    // Scale the hyperbolic columns so that the determinant stays O(1) for long beams.
    m.col(0) /= ch;
    m.col(1) /= ch;
    return m.determinant();
  }

  /// The lowest `count` bending frequencies [Hz] (roots of the determinant by scan + bisection).
  std::vector<double> clamped_free_frequencies(int count) const {
    constexpr double two_pi = 6.283185307179586;
    const double euler_first =
        1.875104 * 1.875104 / (two_pi * length * length) *
        std::sqrt(young * thickness * thickness / (12.0 * density));
    std::vector<double> roots;
    const double step = 0.002 * two_pi * euler_first;
    double low = step;
    double value_low = clamped_free_determinant(low);
    while (static_cast<int>(roots.size()) < count && low < 1e3 * two_pi * euler_first) {
      const double high = low + step;
      const double value_high = clamped_free_determinant(high);
      if ((value_low < 0) != (value_high < 0)) {
        double a = low, b = high, fa = value_low;
        for (int i = 0; i < 200 && b - a > 1e-14 * b; ++i) {
          const double mid = 0.5 * (a + b);
          const double fm = clamped_free_determinant(mid);
          if ((fm < 0) == (fa < 0)) {
            a = mid;
            fa = fm;
          } else {
            b = mid;
          }
        }
        roots.push_back(0.5 * (a + b) / two_pi);
      }
      low = high;
      value_low = value_high;
    }
    return roots;
  }
};

}  // namespace crackle::modal::testing
