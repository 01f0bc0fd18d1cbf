// The exact torque-free rigid body, the reference of the `rigid` experiment
// (docs/physics.md "Rigid bodies (affine bodies)", "The reference"). It is
// not one of the compared integrators: it solves the rigid body's own
// equations, not the affine body's, at a tiny step.
//
// State: the body-frame angular velocity w and the unit quaternion q of the
// orientation R(q) (body -> world). Euler's equations for principal moments
// I = diag(I_1, I_2, I_3) and the quaternion kinematics with the body rate
// (Shuster, "A Survey of Attitude Representations", J. Astronautical
// Sciences 41(4), 1993, eq. 306; Diebel, "Representing Attitude", 2006,
// eq. 158):
//
//     I w' = (I w) x w,        q' = q (0, w) / 2,
//
// both integrated together by the classical RK4 at steps of at most
// `max_step`, q renormalized after every step. Kinetic energy w.I w / 2 and
// the world angular momentum R(q) I w are its first integrals.
//
// The flip (docs/physics.md): the spin axis reverses when the component of
// the angular momentum along the middle principal axis, (R e_m).L = I_m w_m,
// changes sign; `reversals` are the times of these sign changes (linear
// interpolation within a step) and the flip period is the mean time between
// successive reversals.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <atomic>
#include <vector>

namespace springlab {

class RigidReference {
 public:
  // Principal moments I (> 0), body-frame angular velocity w0, orientation R0
  // (a rotation), tracking the sign changes of w's component `middle` (0..2).
  RigidReference(const Eigen::Vector3d& I, const Eigen::Vector3d& w0, const Eigen::Matrix3d& R0,
                 double max_step, int middle);

  // Integrates forward to time t (>= time()), in equal steps of at most
  // max_step that end exactly at t. With `stop` set, it reads it every
  // kStopCheckSteps steps and returns false, short of t, once it is true
  // (a Ctrl-C in a sweep: at reference_step 1e-12 one call was 1e10 steps).
  bool advance_to(double t, const std::atomic<bool>* stop = nullptr);
  static constexpr long kStopCheckSteps = 4096;

  double time() const { return t_; }
  const Eigen::Vector3d& omega() const { return w_; }  // body frame
  Eigen::Matrix3d rotation() const { return q_.toRotationMatrix(); }
  const Eigen::Quaterniond& quaternion() const { return q_; }
  double energy() const { return 0.5 * w_.dot(I_.cwiseProduct(w_)); }
  Eigen::Vector3d angular_momentum() const { return q_ * I_.cwiseProduct(w_); }  // world
  const std::vector<double>& reversals() const { return reversals_; }

 private:
  void step(double h);
  Eigen::Vector3d I_, w_;
  Eigen::Quaterniond q_;
  double t_ = 0.0, max_step_;
  int middle_;
  std::vector<double> reversals_;
};

// The times between successive reversals (empty with fewer than two) and
// their mean (0 when there are fewer than two reversals).
std::vector<double> reversal_intervals(const std::vector<double>& reversals);
double flip_period(const std::vector<double>& reversals);

// The index of the middle principal moment (the one neither largest nor
// smallest; ties: the lower index).
int middle_axis(const Eigen::Vector3d& I);

}  // namespace springlab
