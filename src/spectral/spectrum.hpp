#pragma once
/// \file Amplitude spectra of sampled records with FFTW (r2c), for CSV output and plots.
#include <memory>
#include <string>
#include <vector>

#include "spectral/harmonics.hpp"
#include "spectral/window.hpp"

namespace crackle::spectral {

/// Which part of the record to transform and how.
struct SpectrumOptions {
  /// f [Hz]; with f > 0 the record is cut to whole excitation periods at its end;
  /// 0 = unknown: the whole record.
  double excitation_frequency_hz = 0.0;
  int periods = 0;            ///< with f: the last `periods` periods; 0 = all whole periods
  bool subharmonics = false;  ///< with f: an even number of periods, so f/2 falls on a bin
  /// auto: rectangular when f is given and 1/(f dt) is an integer (every harmonic on an exact
  /// bin, no leakage); flat-top otherwise (peak amplitudes within ~0.1 % wherever the peak
  /// falls between bins). Amplitudes are corrected by the window's coherent gain.
  Window window = Window::automatic;
};

/// One-sided spectrum of peak amplitudes: bin k at frequency k/(N dt), k = 0..N/2, amplitude
/// 2|X_k|/sum(w) (|X_k|/sum(w) at the Nyquist bin), so a sinusoid of peak amplitude A on an exact
/// bin reads A. Bin 0 is the signed (window-weighted) mean X_0/sum(w), the convention of order 0
/// in harmonics.hpp and spectrum.json. Units: frequency [Hz], amplitude [unit of the signal].
struct AmplitudeSpectrum {
  std::vector<double> frequency_hz;
  std::vector<double> amplitude;
  double resolution_hz = 0.0;  ///< 1/(N dt)
  int n_samples = 0;           ///< N, the samples transformed (the last N of the record)
  double start_time = 0.0;     ///< time of the first sample transformed [s]
  Window window = Window::rectangular;
};

/// Computes amplitude spectra and keeps the FFTW plans it made, keyed by length (the 8 most
/// recently used lengths are kept).
///
/// Thread-safety: amplitude_spectrum() may be called concurrently on one analyzer and on
/// different analyzers. Plans are made and destroyed under one process-wide mutex (the FFTW
/// planner is global and not thread-safe); transforms run outside it with
/// fftw_execute_dft_r2c on per-call buffers, which FFTW documents as thread-safe.
class SpectrumAnalyzer {
 public:
  SpectrumAnalyzer();
  ~SpectrumAnalyzer();
  SpectrumAnalyzer(const SpectrumAnalyzer&) = delete;
  SpectrumAnalyzer& operator=(const SpectrumAnalyzer&) = delete;

  /// Spectrum of a record (see SpectrumOptions for the part transformed). InputError on
  /// fewer than 2 samples, non-finite values, or periods asked that do not fit.
  AmplitudeSpectrum amplitude_spectrum(const std::vector<double>& values, const Sampling& sampling,
                                       const SpectrumOptions& options) const;

  /// Plans held now.
  int n_cached_plans() const;

 private:
  struct Cache;
  std::unique_ptr<Cache> cache_;
};

/// CSV text "frequency [Hz],amplitude [<unit>]" with one line per bin (full precision).
std::string spectrum_csv(const AmplitudeSpectrum& spectrum, const std::string& unit);

}  // namespace crackle::spectral
