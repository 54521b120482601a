// The Fourier series of the quadrature (exact/quadrature.hpp, item 2): their sums by
// Clenshaw's recurrence, and their coefficients from samples by a DCT-I computed with one
// complex FFT.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include "spinning_top/integrators/exact/common.hpp"

namespace spinning_top {
namespace exact_detail {

/// N series sharing the argument x: sum_k c[k][i] sin((k+1) x), by Clenshaw's recurrence
/// b_k = c_k + 2 cos(x) b_{k+1} - b_{k+2}, sum = b_1 sin(x).
template <std::size_t N>
std::array<double, N> sine_sums(const std::vector<std::array<double, N>>& c, double cos_x, double sin_x) {
  std::array<double, N> b1{}, b2{};
  const double two_cos = 2.0 * cos_x;
  for (std::size_t k = c.size(); k-- > 0;) {
    for (std::size_t i = 0; i < N; ++i) {
      const double b0 = c[k][i] + two_cos * b1[i] - b2[i];
      b2[i] = b1[i];
      b1[i] = b0;
    }
  }
  for (std::size_t i = 0; i < N; ++i) b1[i] *= sin_x;
  return b1;
}

/// sum_k c[k] cos((k+1) x) by Clenshaw: b_1 cos(x) - b_2.
inline double cosine_sum(const std::vector<double>& c, double cos_x) {
  double b1 = 0.0, b2 = 0.0;
  const double two_cos = 2.0 * cos_x;
  for (std::size_t k = c.size(); k-- > 0;) {
    const double b0 = c[k] + two_cos * b1 - b2;
    b2 = b1;
    b1 = b0;
  }
  return b1 * cos_x - b2;
}

/// In-place radix-2 complex FFT (Cooley-Tukey, decimation in time) of (re, im), n a power of
/// two; the arithmetic written out (std::complex's operator* checks for infinities).
inline void fft(std::vector<double>& re, std::vector<double>& im) {
  const std::size_t n = re.size();
  for (std::size_t i = 1, j = 0; i < n; ++i) {
    std::size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(re[i], re[j]), std::swap(im[i], im[j]);
  }
  // e^{-2 pi i k / n}, each from its own cos and sin, kept for the next transform of this size
  // (the series double their size until converged, and every start repeats the sizes).
  static thread_local std::vector<double> cosine, sine;
  if (cosine.size() != n / 2) {
    cosine.resize(n / 2);
    sine.resize(n / 2);
    for (std::size_t k = 0; k < n / 2; ++k) {
      cosine[k] = std::cos(2.0 * kPi * k / n);
      sine[k] = -std::sin(2.0 * kPi * k / n);
    }
  }
  for (std::size_t length = 2; length <= n; length <<= 1) {
    const std::size_t half = length / 2, stride = n / length;
    for (std::size_t start = 0; start < n; start += length) {
      for (std::size_t k = 0; k < half; ++k) {
        const double wr = cosine[k * stride], wi = sine[k * stride];
        const std::size_t a = start + k, b = a + half;
        const double odd_re = re[b] * wr - im[b] * wi, odd_im = re[b] * wi + im[b] * wr;
        re[b] = re[a] - odd_re, im[b] = im[a] - odd_im;
        re[a] += odd_re, im[a] += odd_im;
      }
    }
  }
}

/// Cosine coefficients a_k, k = 0..n, of two even 2n-periodic functions given by their n + 1
/// samples s_j = g(pi j / n) (the trapezoidal rule, i.e. a DCT-I), through one FFT of the even
/// extensions packed as real and imaginary parts (each has a real spectrum):
/// g(x) = a_0 + sum_{k>=1} a_k cos(k x) to the aliasing error.
inline std::array<std::vector<double>, 2> cosine_coefficients(const std::vector<double>& first,
                                                              const std::vector<double>& second) {
  const std::size_t n = first.size() - 1;
  std::vector<double> re(2 * n), im(2 * n);
  for (std::size_t j = 0; j <= n; ++j) re[j] = first[j], im[j] = second[j];
  for (std::size_t j = 1; j < n; ++j) re[2 * n - j] = first[j], im[2 * n - j] = second[j];
  fft(re, im);
  std::array<std::vector<double>, 2> a = {std::vector<double>(n + 1), std::vector<double>(n + 1)};
  for (std::size_t k = 0; k <= n; ++k) a[0][k] = re[k] / static_cast<double>(n), a[1][k] = im[k] / static_cast<double>(n);
  for (auto& c : a) c[0] *= 0.5, c[n] *= 0.5;
  return a;
}

}  // namespace exact_detail
}  // namespace spinning_top
