#pragma once
/// \file An array from fftw_malloc, for the modules that link FFTW (spectral, sweep); header-only,
/// so core itself does not link FFTW. Plans made on such arrays may use FFTW's SIMD codelets, and a
/// plan made so must run on arrays of the same alignment (new-array execute).
#include <fftw3.h>

#include <cstddef>
#include <new>

namespace crackle {

template <typename T>
struct FftwBuffer {
  explicit FftwBuffer(std::size_t n) : data(static_cast<T*>(fftw_malloc(sizeof(T) * n))) {
    if (!data) throw std::bad_alloc();
  }
  ~FftwBuffer() { fftw_free(data); }
  FftwBuffer(const FftwBuffer&) = delete;
  FftwBuffer& operator=(const FftwBuffer&) = delete;
  T& operator[](std::size_t i) { return data[i]; }
  const T& operator[](std::size_t i) const { return data[i]; }
  T* data;
};

}  // namespace crackle
