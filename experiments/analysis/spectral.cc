#include "experiments/analysis/spectral.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>

#include "integrators/registry/registry.h"
#include "models/model/model.h"
#include "models/core/scene.h"
#include "models/springs/springs.h"

namespace springlab {
namespace {

constexpr int kSteps = 12;       // steps per start
constexpr int kMaxDegree = 4;    // BDF2: (x_n, v_n, x_{n-1}, v_{n-1})
constexpr int kFirstRow = 1;     // windows start after the first step
constexpr double kDropTolerance = 1e-5;  // a drop counts below this fraction of the largest
constexpr double kTinyRate = 1e-6;  // below it, the states' decay rate is the measurement

// w = 1: k = 1, m = 1, a spring of rest length 0 from a fixed anchor (linear
// in every direction).
Scene unit_oscillator() {
  Scene s;
  s.name = "unit-oscillator";
  s.dimension = 2;
  s.particles = {{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 1.0, true},
                 {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::Zero(), 1.0, false}};
  s.block<Springs>() = {{0, 1, 1.0, 0.0, 0.0}};
  return s;
}

// x_n and v_n / w along the spring, n = 0..kSteps, each scaled to max 1.
std::vector<std::vector<double>> sequences(const std::string& name, const IntegratorOptions& o,
                                           double h) {
  const Model model(unit_oscillator());
  std::vector<std::vector<double>> out;
  for (int start = 0; start < 2; ++start) {
    Vector x0 = Vector::Zero(model.dofs()), v0 = Vector::Zero(model.dofs());
    (start == 0 ? x0 : v0)(0) = 1.0;
    auto integrator = make_integrator(name);
    StepResult r = integrator->initialize(model, 0.0, x0, v0, o);
    std::vector<double> xs{x0(0)}, vs{v0(0)};
    for (int n = 1; r.ok && n <= kSteps; ++n) {
      r = integrator->advance_to(n * h);
      xs.push_back(integrator->x()(0));
      vs.push_back(integrator->v()(0));
    }
    if (!r.ok) throw std::runtime_error(name + ": " + r.message);
    out.push_back(xs);
    out.push_back(vs);
  }
  // A fast-growing (unstable) method overflows within kSteps: keep the steps
  // before the first non-finite value in any sequence.
  std::size_t length = out[0].size();
  for (const std::vector<double>& s : out) {
    for (std::size_t n = 0; n < s.size(); ++n) {
      if (!std::isfinite(s[n])) length = std::min(length, n);
    }
  }
  for (std::vector<double>& s : out) s.resize(length);
  return out;
}

// The sequences' common rate r: the largest of each one's mean growth per
// step from its first two steps to its last two. Dividing s_n by r^n scales
// A's eigenvalues by 1/r, so a fast decay (lambda ~ 1e-2 at large w h)
// leaves the windows well conditioned and the degree is not lost in their
// small singular values.
double common_rate(const std::vector<std::vector<double>>& s) {
  double rate = 0.0;
  for (const std::vector<double>& seq : s) {
    const std::size_t n = seq.size();
    const double head = std::abs(seq[1]) + std::abs(seq[2]);
    const double tail = std::abs(seq[n - 1]) + std::abs(seq[n - 2]);
    if (head > 0.0 && tail > 0.0) {
      rate = std::max(rate, std::pow(tail / head, 1.0 / static_cast<double>(n - 3)));
    }
  }
  // (Bounded so that r^n stays a normal number over the kSteps steps.)
  return rate > 0.0 && std::isfinite(rate) ? std::clamp(rate, 1e-20, 1e20) : 1.0;
}

// t_n = s_n / r^n, each sequence then scaled to max |t_n| = 1.
std::vector<std::vector<double>> rescaled(std::vector<std::vector<double>> s, double r) {
  std::vector<std::vector<double>> out;
  for (std::vector<double>& seq : s) {
    double scale = 0.0;
    for (std::size_t n = 0; n < seq.size(); ++n) {
      seq[n] /= std::pow(r, static_cast<double>(n));
      scale = std::max(scale, std::abs(seq[n]));
    }
    if (!(scale > 0.0) || !std::isfinite(scale)) continue;  // nothing to fit
    for (double& value : seq) value /= scale;
    out.push_back(std::move(seq));
  }
  return out;
}

// Rows [s_n ... s_{n+width-1}] of every sequence, n >= kFirstRow.
Eigen::MatrixXd windows(const std::vector<std::vector<double>>& s, int width) {
  const int per = static_cast<int>(s[0].size()) - kFirstRow - width + 1;
  Eigen::MatrixXd m(per * static_cast<int>(s.size()), width);
  int row = 0;
  for (const std::vector<double>& seq : s) {
    for (int n = kFirstRow; n < kFirstRow + per; ++n, ++row) {
      for (int j = 0; j < width; ++j) m(row, j) = seq[n + j];
    }
  }
  return m;
}

}  // namespace

StepSpectrum step_spectrum(const std::string& name, IntegratorOptions options, double wh) {
  if (make_integrator(name)->info().adaptive) {
    throw std::invalid_argument(name + " is adaptive: it has no fixed step to analyse");
  }
  // Newton to its round-off floor (|v| <= 1 here), so the recurrence is the method's.
  options.newton_tol = 1e-13;
  const std::vector<std::vector<double>> raw = sequences(name, options, wh);
  StepSpectrum out;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  out.damping_ratio = out.period_error = nan;
  if (static_cast<int>(raw[0].size()) < kFirstRow + kMaxDegree + 2) {
    // Overflowed within a few steps: |lambda| beyond any measure.
    out.spectral_radius = std::numeric_limits<double>::infinity();
    return out;
  }
  const double r = common_rate(raw);
  const std::vector<std::vector<double>> s = rescaled(raw, r);
  if (s.empty()) return out;  // every sequence zero after the start: A = 0

  // The degree: the numerical rank of the windows.
  const Eigen::MatrixXd hankel = windows(s, kMaxDegree + 1);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(hankel);
  const Eigen::VectorXd sigma = svd.singularValues();
  // The degree d is where the singular values drop most sharply, among the
  // drops to below kDropTolerance of the largest (the states' round-off,
  // which grows with w h, keeps the singular values past the degree above
  // zero but far below the ones before them); kMaxDegree without one.
  int d = kMaxDegree;
  double sharpest = 1.0;
  for (int k = 1; k < sigma.size(); ++k) {
    const double drop = sigma(k) / sigma(k - 1);
    if (sigma(k) <= kDropTolerance * sigma(0) && drop < sharpest) {
      sharpest = drop;
      d = k;
    }
  }
  out.degree = d;

  // s_{n+d} = sum_j c_j s_{n+j}, least squares.
  const Eigen::MatrixXd w = windows(s, d + 1);
  const Eigen::VectorXd c =
      w.leftCols(d).colPivHouseholderQr().solve(w.col(d));
  // The companion matrix of lambda^d - sum_j c_j lambda^j.
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(d, d);
  for (int j = 0; j + 1 < d; ++j) companion(j + 1, j) = 1.0;
  for (int j = 0; j < d; ++j) companion(j, d - 1) = c(j);
  const Eigen::VectorXcd roots = Eigen::EigenSolver<Eigen::MatrixXd>(companion).eigenvalues();

  std::complex<double> principal(0.0, 0.0);
  bool has_pair = false;
  for (std::complex<double> root : roots) {
    root *= r;  // the eigenvalue of A, not of A / r
    out.spectral_radius = std::max(out.spectral_radius, std::abs(root));
    const bool complex_root = std::abs(root.imag()) > 1e-12 * std::abs(root);
    if (complex_root && (!has_pair || std::abs(root) > std::abs(principal))) {
      principal = root;
      has_pair = true;
    }
  }
  if (has_pair) {
    const double angle = std::abs(std::arg(principal));
    out.damping_ratio = -std::log(std::abs(principal)) / angle;
    out.period_error = wh / angle - 1.0;
  }
  // Where a step removes all but kTinyRate of the state, the fit is of
  // numbers at round-off of what it removed, and may find a root far above
  // the decay the states show (xpbd at w h = 251: 0.93 where its ten
  // substeps leave 1e-14): the measured rate is then the spectral radius,
  // and the mode has no period to speak of.
  if (r < kTinyRate && out.spectral_radius > 2.0 * r) {
    out.spectral_radius = r;
    out.damping_ratio = out.period_error = nan;
  }
  return out;
}

}  // namespace springlab
