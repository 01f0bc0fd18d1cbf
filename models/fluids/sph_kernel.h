// The cubic-spline smoothing kernel of smoothed particle hydrodynamics
// (docs/physics.md "Fluids"): the M4 B-spline of Monaghan and Lattanzio
// (1985, Astron. Astrophys. 149:135), as written in Monaghan (1992, Annu.
// Rev. Astron. Astrophys. 30:543) and Monaghan (2005, Rep. Prog. Phys.
// 68:1703). With q = r / h (h the smoothing length, the
// support 2h):
//
//   W(r, h) = sigma_d / h^d  { 1 - 3/2 q^2 + 3/4 q^3   0 <= q < 1
//                            { 1/4 (2 - q)^3           1 <= q < 2
//                            { 0                       q >= 2
//
// normalised so that its integral over the plane (d = 2) or space (d = 3)
// is 1: sigma_2 = 10 / (7 pi), sigma_3 = 1 / pi. The radial derivatives
// dW/dr and d^2W/dr^2 are exact (the spline is C^2 in r); the gradient with
// respect to x_i of W(|x_i - x_j|) is dW/dr (x_i - x_j) / r.
#pragma once

#include <numbers>

namespace springlab {

struct CubicSpline {
  double h = 1.0;      // smoothing length [m]
  double scale = 1.0;  // sigma_d / h^d

  CubicSpline(double smoothing_length, int dimension) : h(smoothing_length) {
    const double sigma = dimension == 2 ? 10.0 / (7.0 * std::numbers::pi) : 1.0 / std::numbers::pi;
    scale = sigma / (dimension == 2 ? h * h : h * h * h);
  }

  double support() const { return 2.0 * h; }

  double value(double r) const {
    const double q = r / h;
    if (q >= 2.0) return 0.0;
    if (q >= 1.0) {
      const double s = 2.0 - q;
      return scale * 0.25 * s * s * s;
    }
    return scale * (1.0 - 1.5 * q * q + 0.75 * q * q * q);
  }

  // dW/dr.
  double slope(double r) const {
    const double q = r / h;
    if (q >= 2.0) return 0.0;
    if (q >= 1.0) {
      const double s = 2.0 - q;
      return -scale * 0.75 * s * s / h;
    }
    return scale * (-3.0 * q + 2.25 * q * q) / h;
  }

  // d^2W/dr^2.
  double curvature(double r) const {
    const double q = r / h;
    if (q >= 2.0) return 0.0;
    if (q >= 1.0) return scale * 1.5 * (2.0 - q) / (h * h);
    return scale * (-3.0 + 4.5 * q) / (h * h);
  }

  // (dW/dr) / r, finite at r = 0 (its limit -3 scale / h^2): the factor
  // that turns x_i - x_j into grad_i W.
  double slope_over_r(double r) const {
    const double q = r / h;
    if (q >= 2.0) return 0.0;
    if (q >= 1.0) {
      const double s = 2.0 - q;
      return -scale * 0.75 * s * s / (h * r);
    }
    return scale * (-3.0 + 2.25 * q) / (h * h);
  }
};

}  // namespace springlab
