// Helpers of the accuracy tests (test_accuracy_*.cpp, test_methods.cpp, test_robustness.cpp):
// small scenes with known answers (../shared/REFERENCE_CASES.md) and the measurements the cases
// name (turning points, recurrence fits, least-squares slopes).
#pragma once

#include <cmath>
#include <utility>
#include <vector>

#include "pbd_cloth/config/scene_config.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace test {

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;

inline double degrees(double radians) { return radians * 180.0 / kPi; }
inline double radians(double degrees) { return degrees * kPi / 180.0; }

// A 1 x n rope with 1 kg particles hanging straight down from particle 0 (pinned) along -z:
// particle (0, c) of the grid starts at origin + R (c spacing, 0, 0), and pitch pi/2 turns +x into
// -z.
inline SceneConfig hangingRope(int n, double spacing, Method method) {
  SceneConfig scene = clothScene(1, n, spacing, method);
  scene.cloth.rpy = Eigen::Vector3d(0.0, kPi / 2.0, 0.0);
  scene.cloth.pinned = {0};
  return scene;
}

// A local extremum of a sampled signal, refined by the parabola through the three samples around
// it: time and value of the vertex.
struct TurningPoint {
  double t = 0.0;
  double value = 0.0;
};

// Extrema of samples y[k] taken at t = t0 + k dt (interior samples only), parabolic vertex.
inline std::vector<TurningPoint> turningPoints(const std::vector<double>& y, double t0, double dt) {
  std::vector<TurningPoint> out;
  for (std::size_t k = 1; k + 1 < y.size(); ++k) {
    const double a = y[k - 1], b = y[k], c = y[k + 1];
    const bool maximum = b > a && b >= c, minimum = b < a && b <= c;
    if (!maximum && !minimum) continue;
    const double curvature = a - 2.0 * b + c;
    const double shift = 0.5 * (a - c) / curvature;  // vertex offset in samples, |shift| <= 1/2
    out.push_back({t0 + (static_cast<double>(k) + shift) * dt, b - 0.25 * (a - c) * shift});
  }
  return out;
}

// Least-squares slope of y against x.
inline double fitSlope(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sx += x[k];
    sy += y[k];
    sxx += x[k] * x[k];
    sxy += x[k] * y[k];
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// A sampled linear oscillator (any linear one-step scheme on (x, v)) obeys the two-term
// recurrence y[k+1] = a y[k] + b y[k-1], a = 2 r cos(phi), b = -r^2, where r e^{+-i phi} are the
// eigenvalues of the step map. Fitted by least squares; returns {r, phi}: amplitude factor and
// phase advance per sample.
inline std::pair<double, double> fitRecurrence(const std::vector<double>& y) {
  double s11 = 0.0, s12 = 0.0, s22 = 0.0, r1 = 0.0, r2 = 0.0;
  for (std::size_t k = 1; k + 1 < y.size(); ++k) {
    s11 += y[k] * y[k];
    s12 += y[k] * y[k - 1];
    s22 += y[k - 1] * y[k - 1];
    r1 += y[k + 1] * y[k];
    r2 += y[k + 1] * y[k - 1];
  }
  const double det = s11 * s22 - s12 * s12;
  const double a = (r1 * s22 - r2 * s12) / det;
  const double b = (s11 * r2 - s12 * r1) / det;
  const double r = std::sqrt(-b);
  return {r, std::acos(a / (2.0 * r))};
}

}  // namespace test
}  // namespace pbd_cloth
