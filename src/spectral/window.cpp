#include "spectral/window.hpp"

#include <cmath>

#include "core/errors.hpp"

namespace crackle::spectral {

Window parse_window(const std::string& name) { return parse_word(kWindowWords, name, "window"); }

const char* window_name(Window window) { return text_of(kWindowWords, window); }

std::vector<double> window_values(Window window, int n) {
  std::vector<double> w(static_cast<std::size_t>(n > 0 ? n : 0), 1.0);
  const double two_pi = 2.0 * M_PI;
  for (int i = 0; i < n; ++i) {
    const double x = two_pi * i / n;
    if (window == Window::hann) {
      w[i] = 0.5 - 0.5 * std::cos(x);
    } else if (window == Window::flattop) {
      w[i] = 0.21557895 - 0.41663158 * std::cos(x) + 0.277263158 * std::cos(2 * x) -
             0.083578947 * std::cos(3 * x) + 0.006947368 * std::cos(4 * x);
    }
  }
  return w;
}

}  // namespace crackle::spectral
