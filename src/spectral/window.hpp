#pragma once
/// \file Analysis windows for harmonic extraction and amplitude spectra.
#include <string>
#include <vector>

#include "core/choices.hpp"

namespace crackle::spectral {

/// Window applied to a record before a DFT (core/choices.hpp, with its words): `automatic` lets the
/// analysis choose (see HarmonicOptions and SpectrumOptions); the others are applied as asked.
using crackle::Window;

/// Parses "auto", "rectangular", "hann" or "flattop"; InputError otherwise.
Window parse_window(const std::string& name);

/// Name of a window as parse_window() reads it.
const char* window_name(Window window);

/// The n periodic (DFT-even) window values w_i, i = 0..n-1:
/// rectangular 1; Hann \f$\tfrac12 - \tfrac12\cos(2\pi i/n)\f$; flat-top
/// \f$\sum_{m=0}^{4} (-1)^m a_m \cos(2\pi m i/n)\f$ with the coefficients of MATLAB's
/// flattopwin (a0 = 0.21557895, ...). A peak amplitude is \f$2|X_k| / \sum_i w_i\f$.
std::vector<double> window_values(Window window, int n);

}  // namespace crackle::spectral
