#pragma once
// Synthetic signals with known harmonic content, shared by the spectral tests.
#include <cmath>
#include <complex>
#include <vector>

#include "spectral/harmonics.hpp"

namespace crackle::spectral::testing {

/// One sinusoid A cos(2 pi k f t + phi); order 0 is the constant A.
struct Component {
  double order;
  double amplitude;
  double phase;
};

/// sum of the components at absolute time t.
inline double evaluate(const std::vector<Component>& components, double frequency, double t) {
  double x = 0.0;
  for (const Component& c : components) {
    x += c.order == 0.0 ? c.amplitude
                        : c.amplitude * std::cos(2.0 * M_PI * c.order * frequency * t + c.phase);
  }
  return x;
}

/// The components the tests use: a mean, orders 1/2 .. 3 (5/2 absent).
inline std::vector<Component> rich_content() {
  return {{0.0, -0.3, 0.0}, {0.5, 0.05, 0.3}, {1.0, 1.0, -1.2},
          {1.5, 0.02, 2.5}, {2.0, 0.1, 0.7},  {3.0, 0.03, -2.9}};
}

/// Expected complex amplitude of an order (0 when absent).
inline std::complex<double> expected(const std::vector<Component>& components, double order) {
  for (const Component& c : components) {
    if (c.order == order) return std::polar(c.amplitude, c.phase);
  }
  return 0.0;
}

/// n samples of a function at t_i = t0 + i dt.
template <typename Function>
std::vector<double> sample(Function&& x, const Sampling& sampling, long n) {
  std::vector<double> values(n);
  for (long i = 0; i < n; ++i) values[i] = x(sampling.start_time + i * sampling.time_step);
  return values;
}

}  // namespace crackle::spectral::testing
