#include "experiments/analysis/rigid_reference.h"

#include <cmath>
#include <stdexcept>

namespace springlab {
namespace {

struct Rates {
  Eigen::Vector3d dw;
  Eigen::Vector4d dq;  // (w, x, y, z)
};

// w' = I^-1 ((I w) x w), q' = q (0, w) / 2 (Hamilton product).
Rates rates(const Eigen::Vector3d& I, const Eigen::Vector3d& w, const Eigen::Vector4d& q) {
  Rates r;
  r.dw = (I.cwiseProduct(w)).cross(w).cwiseQuotient(I);
  const double qw = q[0];
  const Eigen::Vector3d qv = q.tail<3>();
  r.dq[0] = -0.5 * qv.dot(w);
  r.dq.tail<3>() = 0.5 * (qw * w + qv.cross(w));
  return r;
}

}  // namespace

RigidReference::RigidReference(const Eigen::Vector3d& I, const Eigen::Vector3d& w0,
                               const Eigen::Matrix3d& R0, double max_step, int middle)
    : I_(I), w_(w0), q_(R0), max_step_(max_step), middle_(middle) {
  if (!(I.minCoeff() > 0.0) || !(max_step > 0.0) || middle < 0 || middle > 2) {
    throw std::invalid_argument("RigidReference: moments and step must be positive");
  }
  q_.normalize();
}

void RigidReference::step(double h) {
  const Eigen::Vector4d q(q_.w(), q_.x(), q_.y(), q_.z());
  const Rates k1 = rates(I_, w_, q);
  const Rates k2 = rates(I_, w_ + 0.5 * h * k1.dw, q + 0.5 * h * k1.dq);
  const Rates k3 = rates(I_, w_ + 0.5 * h * k2.dw, q + 0.5 * h * k2.dq);
  const Rates k4 = rates(I_, w_ + h * k3.dw, q + h * k3.dq);
  const Eigen::Vector3d w = w_ + h / 6.0 * (k1.dw + 2.0 * k2.dw + 2.0 * k3.dw + k4.dw);
  Eigen::Vector4d qn = q + h / 6.0 * (k1.dq + 2.0 * k2.dq + 2.0 * k3.dq + k4.dq);
  qn.normalize();
  const double before = w_[middle_], after = w[middle_];
  if ((before > 0.0 && after <= 0.0) || (before < 0.0 && after >= 0.0)) {
    reversals_.push_back(t_ + h * before / (before - after));
  }
  w_ = w;
  q_ = Eigen::Quaterniond(qn[0], qn[1], qn[2], qn[3]);
  t_ += h;
}

bool RigidReference::advance_to(double t, const std::atomic<bool>* stop) {
  if (!(t >= t_)) throw std::invalid_argument("RigidReference: cannot go back in time");
  const double span = t - t_;
  if (span == 0.0) return true;
  const long n = static_cast<long>(std::ceil(span / max_step_));
  const double start = t_;
  for (long k = 1; k <= n; ++k) {
    if (stop != nullptr && k % kStopCheckSteps == 0 && stop->load(std::memory_order_relaxed)) {
      return false;  // t_ is where it stopped
    }
    const double next = k == n ? t : start + span * static_cast<double>(k) / static_cast<double>(n);
    step(next - t_);
  }
  t_ = t;
  return true;
}

std::vector<double> reversal_intervals(const std::vector<double>& reversals) {
  std::vector<double> out;
  for (std::size_t k = 1; k < reversals.size(); ++k) out.push_back(reversals[k] - reversals[k - 1]);
  return out;
}

double flip_period(const std::vector<double>& reversals) {
  if (reversals.size() < 2) return 0.0;
  return (reversals.back() - reversals.front()) / static_cast<double>(reversals.size() - 1);
}

int middle_axis(const Eigen::Vector3d& I) {
  int lo = 0, hi = 0;
  I.minCoeff(&lo);
  I.maxCoeff(&hi);
  if (lo == hi) return lo == 0 ? 1 : 0;
  return 3 - lo - hi;
}

}  // namespace springlab
