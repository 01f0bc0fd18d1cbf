#pragma once

#include "models/core/mechanical_system.h"

namespace springlab {

// Friction's normal forces held at x (the step's or substep's start) while
// the step is solved, and released when it ends, on every path out
// (MechanicalSystem::lag_normal_forces): friction then derives from a
// dissipation potential, so an implicit step minimizes an incremental
// potential. Newton's steps also pass the start velocity v and the step h
// (the bodies' contact set is found along x + h v); vertex block descent
// passes x alone. Used by Newton's steps and by vertex block descent.
class LaggedNormalForces {
 public:
  LaggedNormalForces(const MechanicalSystem& system, const Vector& x, const Vector* v = nullptr,
                     double h = 0.0)
      : system_(system), x_(x), v_(v), h_(h) {
    system_.lag_normal_forces(&x, v, h);
  }
  // The step's start again, for another attempt at the step: the contacts
  // a previous attempt found at its iterates (follow_lagged_contacts) are
  // dropped, so that the attempt starts where the step's contacts hold.
  // (x and v are kept by reference: they must outlive this object, as the
  // step's state does.)
  void again() const { system_.lag_normal_forces(&x_, v_, h_); }
  ~LaggedNormalForces() { system_.lag_normal_forces(nullptr, nullptr, 0.0); }
  LaggedNormalForces(const LaggedNormalForces&) = delete;
  LaggedNormalForces& operator=(const LaggedNormalForces&) = delete;

 private:
  const MechanicalSystem& system_;
  const Vector& x_;
  const Vector* v_;
  double h_;
};

}  // namespace springlab
