#pragma once
/// \file Free-vibration (ring-down) analysis of a plucked or tapped part, frequency-response
/// estimates from an impact test, and the half-sine impact pulse (MODEL.md §5: a breathing
/// crack rings at the bilinear frequency \f$2 f_u f_o / (f_u + f_o)\f$ and its response carries
/// 2f, 3f, ...).
///
/// Conventions of harmonics.hpp: peak amplitudes, cosine phases at absolute time
/// \f$t_i = t_0 + i\,\Delta t\f$ (Sampling), orders k = 1..H and, with sub-harmonics,
/// k = 1/2, 3/2, ..., H - 1/2 of the ring-down frequency f.
#include <complex>
#include <limits>
#include <vector>

#include "spectral/harmonics.hpp"

namespace crackle::spectral {

/// What to measure in a ring-down record.
struct RingdownOptions {
  int max_order = 3;          ///< H >= 1: orders 1..H of the ring-down frequency
  bool subharmonics = false;  ///< also orders 1/2, 3/2, ..., H - 1/2
  /// [s], absolute: the analysis starts at the first sample at or after this time (skips the
  /// drive or an initial transient); the default takes the whole record.
  double start_time = -std::numeric_limits<double>::infinity();
  /// Periods of f per envelope window (>= 1; even with sub-harmonics). Shrunk so that at least
  /// three windows fit (two with sub-harmonics and a short record).
  int window_periods = 4;
};

/// One order of the ring-down.
struct RingdownHarmonic {
  double order = 0.0;         ///< k: 0.5, 1, 1.5, 2, ...
  double frequency_hz = 0.0;  ///< k f [Hz]
  /// A_k [unit of the signal], peak, with the fitted exponential decay removed, i.e. the
  /// amplitude the order has at the analysis start time.
  double amplitude = 0.0;
  double relative_amplitude = 0.0;  ///< A_k / A_1 (1 for the fundamental)
  double phase_rad = 0.0;           ///< phi_k in (-pi, pi], at absolute time
};

/// Amplitudes of every order over one envelope window of whole periods (no decay removed).
struct EnvelopeWindow {
  double start_time = 0.0;        ///< [s]
  double end_time = 0.0;          ///< [s], start_time + window_periods / f
  std::vector<double> amplitude;  ///< A_k over the window, same orders as the harmonics
};

/// Result of analyse_ringdown().
struct RingdownAnalysis {
  /// f [Hz]: the dominant (for a damped linear mode: the damped) frequency, found as the
  /// maximum of the Hann-windowed DTFT magnitude (~1e-8 relative over 60 periods).
  double frequency_hz = 0.0;
  /// \f$\sigma\f$ [1/s]: the envelope of the fundamental decays as \f$e^{-\sigma t}\f$
  /// (least-squares fit of log A_1 against the envelope window centres); negative when it grows.
  double decay_rate_per_s = 0.0;
  /// \f$\delta = \sigma / f\f$, the log of the ratio of successive peaks.
  double logarithmic_decrement = 0.0;
  /// \f$\zeta = \delta / \sqrt{4\pi^2 + \delta^2}\f$, exact for a linear mode.
  double damping_ratio = 0.0;
  /// \f$f_n = \sqrt{f^2 + (\sigma / 2\pi)^2}\f$ [Hz], the undamped frequency of a linear mode.
  double natural_frequency_hz = 0.0;
  /// Root-mean-square residual of the log A_1 fit: 0 for an exact exponential decay, larger
  /// when the decay is not exponential (friction, amplitude-dependent damping).
  double decay_fit_residual = 0.0;
  double mean = 0.0;  ///< mean of the analysed samples [unit of the signal]

  std::vector<RingdownHarmonic> harmonics;  ///< ascending order, the fundamental included
  double start_time = 0.0;                  ///< analysed periods [start_time, end_time) [s]
  double end_time = 0.0;
  int periods = 0;  ///< whole periods of f analysed (even with sub-harmonics)

  int window_periods = 0;                ///< periods per envelope window actually used
  std::vector<EnvelopeWindow> envelope;  ///< consecutive windows from start_time

  /// The harmonic of order k; InputError if absent.
  const RingdownHarmonic& at(double order) const;
};

/// Ring-down analysis of a free-vibration record.
///
/// 1. f: peak of the zero-padded (x4) FFT of the Hann-windowed, mean-free record, then the root
///    of \f$\tfrac{d}{df}|X_w(f)|^2\f$ within one bin (regula falsi). For a real decaying
///    sinusoid the windowed magnitude is symmetric about the damped frequency, so the only
///    bias is leakage from -f and from other orders (~1e-8 relative over 60 periods).
/// 2. Envelope: rectangular single-bin DFTs at k f over consecutive windows of whole periods,
///    on a grid of whole periods interpolated from the samples (8-point Lagrange, as in
///    extract_harmonics). For \f$e^{-\sigma t}\cos(\omega t)\f$ every window sees the same
///    leakage factor, so the slope of log A_1 against time is \f$-\sigma\f$ up to the
///    interpolation error.
/// 3. Harmonics: the same DFT over all whole periods of \f$x(t)\,e^{\sigma (t - t_s)}\f$, the
///    record with the fitted decay removed (t_s = start_time of the analysis).
///
/// InputError on a bad time step or options, non-finite samples, a record without oscillation
/// or holding fewer than 4 periods of f, or fewer than 4 samples per period of order H.
RingdownAnalysis analyse_ringdown(const std::vector<double>& samples, const Sampling& sampling,
                                  const RingdownOptions& options);


/// Frequency-response estimate H(f) = X(f) / F(f) from one impact record.
struct FrequencyResponse {
  std::vector<double> frequency_hz;            ///< bins k / (N dt) kept, ascending [Hz]
  std::vector<std::complex<double>> response;  ///< H [response unit / force unit]
  std::vector<double> magnitude;               ///< |H|
  std::vector<double> phase_rad;               ///< arg H in (-pi, pi]
  double resolution_hz = 0.0;                  ///< 1 / (N dt)
};

/// H(f) = X(f)/F(f) from the DFTs of the whole response and force records (rectangular: the
/// response of an impact test should have died out by the end of the record; what remains
/// leaks). Keeps the bins with f_min <= f <= f_max where |F| > force_threshold max|F| (the max
/// over all bins), so the bins near the zeros of a pulse spectrum are dropped. Direct DFT of
/// the kept bins: O(N n_bins). InputError on records of different or < 2 lengths, a bad time
/// step, non-finite values, f_min > f_max, or a force with no bin above the threshold.
FrequencyResponse estimate_frf(const std::vector<double>& response,
                               const std::vector<double>& force, const Sampling& sampling,
                               double f_min, double f_max, double force_threshold = 1e-3);

/// Frequencies [Hz] of the local maxima of |H| (over three adjacent bins) of at least
/// relative_threshold max|H|, refined by a parabola through the three magnitudes; ascending.
std::vector<double> frf_peaks(const FrequencyResponse& frf, double relative_threshold = 0.1);

/// Half-sine impact pulse: peak sin(pi (t - start) / duration) for start <= t <= start +
/// duration, 0 elsewhere [force unit]. InputError on duration <= 0.
double half_sine_pulse(double t, double start, double duration, double peak);

/// Its Fourier magnitude \f$|P(f)| = \left|\int p(t) e^{-2\pi i f t} dt\right|
/// = \text{peak}\,d\,\frac{|\mathrm{sinc}(1/2 - f d)|}{1 + 2 f d}\f$ [force unit s], with
/// sinc(v) = sin(pi v)/(pi v): 2 peak d / pi at f = 0, first zero at f = 1.5 / d, then zeros at
/// (m + 1/2)/d, envelope falling as 1/f^2. InputError on duration <= 0.
double half_sine_pulse_spectrum(double frequency_hz, double duration, double peak);

}  // namespace crackle::spectral
